#include "io/isolate.h"

#include <fmt/format.h>

#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdint>
#include <cstring>

#include <fcntl.h>
#include <poll.h>
#include <sys/wait.h>
#include <unistd.h>

#if defined(__has_feature)
#if __has_feature(address_sanitizer)
#define FF_ISOLATE_ASAN 1
#endif
#endif
#if defined(__SANITIZE_ADDRESS__) && !defined(FF_ISOLATE_ASAN)
#define FF_ISOLATE_ASAN 1
#endif
#ifdef FF_ISOLATE_ASAN
#include <sanitizer/common_interface_defs.h>
#endif

namespace ff::io {

std::string one_line(std::string_view s, std::size_t max_length) {
  std::string out;
  out.reserve(std::min(s.size(), max_length + 3));
  for (const char c : s) {
    if (static_cast<unsigned char>(c) < 0x20 || c == ' ' || c == 0x7f) {
      if (!out.empty() && out.back() != ' ') out.push_back(' ');
    } else {
      out.push_back(c);
    }
  }
  while (!out.empty() && out.back() == ' ') out.pop_back();
  if (out.size() > max_length) {
    out.resize(max_length);
    out += "...";
  }
  return out;
}

namespace {

/// Writes all of `data` (the child's side); false when the parent has gone.
bool write_all(int fd, const char* data, std::size_t n) {
  while (n > 0) {
    const ssize_t k = ::write(fd, data, n);
    if (k < 0 && errno == EINTR) continue;
    if (k <= 0) return false;
    data += k;
    n -= static_cast<std::size_t>(k);
  }
  return true;
}

[[noreturn]] void child_main(int out, const std::function<std::string()>& work) {
  // A crash in the parser must end this process quietly: not run the parent's crash handlers (a fuzzer's, which
  // would write the input as its own crash), not print a sanitizer's report over the parent's output.
  for (const int sig : {SIGSEGV, SIGBUS, SIGABRT, SIGILL, SIGFPE, SIGTRAP, SIGALRM, SIGTERM, SIGINT})
    std::signal(sig, SIG_DFL);
  std::signal(SIGPIPE, SIG_IGN);  // a vanished parent: write() fails instead of killing
#ifdef FF_ISOLATE_ASAN
  __sanitizer_set_death_callback(nullptr);
#endif
  if (const int null = ::open("/dev/null", O_WRONLY); null >= 0) ::dup2(null, STDERR_FILENO), ::dup2(null, STDOUT_FILENO);

  const std::string bytes = work();
  const std::uint64_t n = bytes.size();
  const bool ok = write_all(out, reinterpret_cast<const char*>(&n), sizeof n) && write_all(out, bytes.data(), bytes.size());
  ::_exit(ok ? 0 : 3);
}

std::string signal_name(int sig) {
  const char* d = ::strsignal(sig);
  return fmt::format("signal {}{}{}", sig, d != nullptr ? ", " : "", d != nullptr ? d : "");
}

}  // namespace

Result<std::string> run_isolated(const std::function<std::string()>& work, const std::string& what,
                                 const IsolateOptions& options) {
  if (!(options.timeout_s > 0.0)) return param_error(fmt::format("isolate timeout {} s must be > 0", options.timeout_s));
  int fds[2];
  if (::pipe2(fds, O_CLOEXEC) != 0) return io_error(fmt::format("cannot start {}: pipe: {}", what, std::strerror(errno)));
  const pid_t pid = ::fork();
  if (pid < 0) {
    const int e = errno;
    ::close(fds[0]), ::close(fds[1]);
    return io_error(fmt::format("cannot start {}: fork: {}", what, std::strerror(e)));
  }
  if (pid == 0) {
    ::close(fds[0]);
    child_main(fds[1], work);
  }
  ::close(fds[1]);

  // Read until end of file or the deadline; the answer is a 64-bit length and that many bytes.
  using Clock = std::chrono::steady_clock;
  const auto deadline = Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(options.timeout_s));
  std::string got;
  bool timed_out = false, read_failed = false;
  char buf[1 << 16];
  for (;;) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count();
    if (left <= 0) {
      timed_out = true;
      break;
    }
    pollfd p{fds[0], POLLIN, 0};
    const int r = ::poll(&p, 1, static_cast<int>(std::min<long long>(left, 1000)));
    if (r < 0 && errno == EINTR) continue;
    if (r < 0) {
      read_failed = true;
      break;
    }
    if (r == 0) continue;
    const ssize_t k = ::read(fds[0], buf, sizeof buf);
    if (k < 0 && errno == EINTR) continue;
    if (k < 0) {
      read_failed = true;
      break;
    }
    if (k == 0) break;
    got.append(buf, static_cast<std::size_t>(k));
  }
  ::close(fds[0]);
  if (timed_out || read_failed) ::kill(pid, SIGKILL);

  int status = 0;
  pid_t w;
  while ((w = ::waitpid(pid, &status, 0)) < 0 && errno == EINTR) {
  }
  if (timed_out)
    return input_error(fmt::format("{} did not finish within {} s (stopped)", what, options.timeout_s));
  if (read_failed) return io_error(fmt::format("{}: reading its answer failed", what));
  if (w == pid && WIFSIGNALED(status))
    return input_error(fmt::format("{} crashed on it ({})", what, signal_name(WTERMSIG(status))));
  if (w == pid && WIFEXITED(status) && WEXITSTATUS(status) != 0)
    return input_error(fmt::format("{} failed (its process exited with status {})", what, WEXITSTATUS(status)));
  // w < 0 (ECHILD: the program ignores SIGCHLD, so no status is kept): the answer's completeness decides.
  std::uint64_t n = 0;
  if (got.size() < sizeof n) return input_error(fmt::format("{} ended without an answer", what));
  std::memcpy(&n, got.data(), sizeof n);
  if (n != got.size() - sizeof n) return input_error(fmt::format("{} ended with an incomplete answer", what));
  got.erase(0, sizeof n);
  return got;
}

}  // namespace ff::io
