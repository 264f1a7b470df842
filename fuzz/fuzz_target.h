#pragma once
// One libFuzzer target per fuzz/fuzz_<name>.cpp, written as
//
//   FF_FUZZ_TARGET(name) { ... data, size ...; return 0; }
//
// The fuzz preset (clang, -fsanitize=fuzzer) builds each file into its own fuzzer, where the body is
// LLVMFuzzerTestOneInput. The test suite (tests/fuzz/replay_test.cpp, built with FF_FUZZ_REPLAY by the ordinary
// presets) compiles the same files into one program, where each body is a function registered under its name, and
// replays every file of fuzz/corpus/<name>/ and fuzz/crashes/<name>/ through it.
//
// What every target checks besides "no signal, no sanitizer report, no exception": an input that is refused is
// refused with one Error of kind Input or Param (exit code 2 in the CLI) whose message is one printable line; an
// input that is accepted gives a value that holds what the reader promises (check_*() in each target). A broken
// property aborts, which libFuzzer reports as a crash and the replay test as a failure.
#include "core/error.h"

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <span>
#include <string_view>
#include <vector>

namespace ff::fuzz {

using TargetFn = int (*)(const std::uint8_t* data, std::size_t size);

[[noreturn]] inline void fail(const char* what, const char* file, int line) {
  std::fprintf(stderr, "fuzz check failed: %s (%s:%d)\n", what, file, line);
  std::abort();
}

#define FF_FUZZ_CHECK(cond) ((cond) ? void(0) : ::ff::fuzz::fail(#cond, __FILE__, __LINE__))

/// One line: no control character (a newline, a carriage return, an escape sequence) and not empty.
inline bool one_printable_line(std::string_view s) {
  if (s.empty()) return false;
  for (const char c : s)
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) return false;
  return true;
}

/// FF_FUZZ_VERBOSE=1 in the environment: print every refusal (to see why a seed or a crash input is refused).
inline bool verbose() {
  static const bool v = std::getenv("FF_FUZZ_VERBOSE") != nullptr;
  return v;
}

/// A refused input: an Input or Param error (the CLI's exit code 2) whose message is one printable line.
inline void check_refusal(const Error& e) {
  if (verbose()) std::fprintf(stderr, "refused: %s\n", e.message.c_str());
  if (!e.is_input() || !one_printable_line(e.message))
    std::fprintf(stderr, "refusal: kind %d, message \"%.*s\"\n", static_cast<int>(e.kind),
                 static_cast<int>(e.message.size()), e.message.data());
  FF_FUZZ_CHECK(e.is_input());
  FF_FUZZ_CHECK(one_printable_line(e.message));
}

inline std::string_view as_text(const std::uint8_t* data, std::size_t size) {
  return {reinterpret_cast<const char*>(data), size};
}

#ifdef FF_FUZZ_REPLAY
struct Registered {
  const char* name;
  TargetFn fn;
};
/// Every target compiled into the replay test, in no particular order (tests/fuzz/replay_test.cpp defines it).
std::vector<Registered>& registry();
struct Register {
  Register(const char* name, TargetFn fn) { registry().push_back({name, fn}); }
};
#endif

}  // namespace ff::fuzz

#ifdef FF_FUZZ_REPLAY
#define FF_FUZZ_TARGET(name)                                                                  \
  static int ff_fuzz_##name(const std::uint8_t* data, std::size_t size);                     \
  static const ::ff::fuzz::Register ff_fuzz_register_##name(#name, &ff_fuzz_##name);         \
  static int ff_fuzz_##name(const std::uint8_t* data, std::size_t size)
#else
#define FF_FUZZ_TARGET(name) extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
#endif
