// run_isolated (io/isolate.h): the child's bytes come back whole, and every way a child can fail (a crash, an
// abort, an exit status, a hang, a missing answer) is an Input error of one line, with the parent untouched: its
// crash handlers do not run in the child and the child's stderr does not reach it.
#include "io/isolate.h"

#include <gtest/gtest.h>

#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <thread>
#include <vector>

#include <unistd.h>

namespace ff::io {
namespace {

TEST(RunIsolated, ReturnsTheChildsBytesWholeSmallAndLarge) {
  auto small = run_isolated([] { return std::string("abc\0def", 7); }, "small");
  ASSERT_TRUE(small.has_value()) << small.error().message;
  EXPECT_EQ(*small, std::string("abc\0def", 7));

  auto empty = run_isolated([] { return std::string(); }, "empty");
  ASSERT_TRUE(empty.has_value()) << empty.error().message;
  EXPECT_EQ(*empty, "");

  // More than a pipe holds (64 KiB), so the parent must read while the child writes.
  auto large = run_isolated(
      [] {
        std::string s(48u << 20, '\0');
        for (std::size_t i = 0; i < s.size(); ++i) s[i] = static_cast<char>(i * 2654435761u >> 24);
        return s;
      },
      "large");
  ASSERT_TRUE(large.has_value()) << large.error().message;
  ASSERT_EQ(large->size(), 48u << 20);
  for (std::size_t i = 0; i < large->size(); i += 4093) ASSERT_EQ((*large)[i], static_cast<char>(i * 2654435761u >> 24));
}

void expect_input_error(const Result<std::string>& r, const std::string& contains) {
  ASSERT_FALSE(r.has_value());
  EXPECT_EQ(r.error().kind, Error::Kind::Input);
  EXPECT_EQ(r.error().message.find('\n'), std::string::npos);
  EXPECT_NE(r.error().message.find(contains), std::string::npos) << r.error().message;
}

// Set by the parent's SIGSEGV handler below; a child must never run it (it would write the parent's crash report,
// as libFuzzer's does).
volatile std::sig_atomic_t g_parent_handler_ran = 0;
void parent_handler(int) { g_parent_handler_ran = 1; }

TEST(RunIsolated, ACrashOrAnAbortInTheChildIsAnInputErrorNamingTheSignal) {
  struct sigaction sa {}, old {};
  sa.sa_handler = parent_handler;
  ASSERT_EQ(sigaction(SIGSEGV, &sa, &old), 0);
  auto segv = run_isolated(
      [] {
        std::raise(SIGSEGV);  // with the parent's handler this would return and the child answer "survived"
        return std::string("survived");
      },
      "the segfaulting work");
  sigaction(SIGSEGV, &old, nullptr);
  expect_input_error(segv, "the segfaulting work crashed on it (signal 11");
  EXPECT_EQ(g_parent_handler_ran, 0);

  expect_input_error(run_isolated([]() -> std::string { std::abort(); }, "aborting"), "aborting crashed on it (signal 6");
}

TEST(RunIsolated, AnExitWithoutAWholeAnswerIsAnInputError) {
  expect_input_error(run_isolated([]() -> std::string { ::_exit(7); }, "exiting"), "exiting failed (its process exited with status 7)");
  expect_input_error(run_isolated([]() -> std::string { ::_exit(0); }, "silent"), "silent ended without an answer");
}

TEST(RunIsolated, AHangIsStoppedAtTheTimeout) {
  IsolateOptions o;
  o.timeout_s = 0.3;
  const auto start = std::chrono::steady_clock::now();
  auto r = run_isolated(
      []() -> std::string {
        for (;;) ::pause();
      },
      "hanging", o);
  const double took = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  expect_input_error(r, "hanging did not finish within 0.3 s");
  EXPECT_LT(took, 30.0) << "the child must be killed, not waited for";

  o.timeout_s = 0.0;
  auto bad = run_isolated([] { return std::string(); }, "x", o);
  ASSERT_FALSE(bad.has_value());
  EXPECT_EQ(bad.error().kind, Error::Kind::Param);
}

TEST(RunIsolated, TheChildsOutputDoesNotReachTheParent) {
  testing::internal::CaptureStderr();
  testing::internal::CaptureStdout();
  auto r = run_isolated(
      [] {
        std::fprintf(stderr, "child stderr\n");
        std::printf("child stdout\n");
        std::fflush(nullptr);
        return std::string("ok");
      },
      "chatty");
  EXPECT_EQ(testing::internal::GetCapturedStdout(), "");
  EXPECT_EQ(testing::internal::GetCapturedStderr(), "");
  ASSERT_TRUE(r.has_value()) << r.error().message;
  EXPECT_EQ(*r, "ok");
}

TEST(RunIsolated, WorksFromSeveralThreadsAtOnce) {
  std::vector<std::thread> threads;
  std::vector<int> ok(8, 0);
  for (int t = 0; t < 8; ++t)
    threads.emplace_back([&, t] {
      for (int k = 0; k < 5; ++k) {
        auto r = run_isolated([t, k] { return std::string(static_cast<std::size_t>(1000 * t + k), 'x'); }, "thread");
        ok[t] += r.has_value() && r->size() == static_cast<std::size_t>(1000 * t + k);
      }
    });
  for (auto& th : threads) th.join();
  for (int t = 0; t < 8; ++t) EXPECT_EQ(ok[t], 5) << "thread " << t;
}

// A child that refused its file answers with the Error's kind and message (mesh and skin imports alike): the parent
// takes it as the file's one-line error only when it is an Input error with something printable and nothing after.
TEST(AnswerReader, AChildsRefusalIsOneLineInputErrorOrGarbled) {
  const auto refusal = [](Error::Kind kind, const std::string& message, const std::string& after = "") {
    AnswerWriter w;
    w.put(static_cast<std::uint8_t>(kind));
    w.put_string(message);
    return w.take() + after;
  };
  std::string got;
  const std::string ok = refusal(Error::Kind::Input, "m.obj:\tbad\n\nline ");
  EXPECT_TRUE(AnswerReader(ok).get_input_error(got));
  EXPECT_EQ(got, "m.obj: bad line");
  EXPECT_FALSE(AnswerReader(refusal(Error::Kind::Numerical, "m.obj: x")).get_input_error(got));
  EXPECT_FALSE(AnswerReader(refusal(Error::Kind::Cancelled, "m.obj: x")).get_input_error(got));
  EXPECT_FALSE(AnswerReader(refusal(Error::Kind::Input, "\n\t ")).get_input_error(got));
  EXPECT_FALSE(AnswerReader(refusal(Error::Kind::Input, "m.obj: x", "!")).get_input_error(got));
  for (std::size_t cut = 0; cut < ok.size(); ++cut) EXPECT_FALSE(AnswerReader(ok.substr(0, cut)).get_input_error(got)) << cut;
  EXPECT_EQ(one_line(std::string(400, 'x')).size(), 303u);  // cut at 300, marked "..."
}

}  // namespace
}  // namespace ff::io
