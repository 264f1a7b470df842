#pragma once
// Running a parser we do not own in a child process, so that its bugs cannot take the program down.
//
// Assimp 5.2.5 (Debian 12's) has heap overflows on malformed files that later Assimp releases fixed (OBJ lines and
// faces, PLY, OFF counts, …): under the fuzzer one of them corrupted the heap so that a later, unrelated free
// aborted. No check of ours before Assimp can cover every such bug, so load_mesh runs Assimp in a forked child:
// a crash, an abort, a hang or a runaway allocation there ends the child, and the parent turns it into one line
// naming the file. The child sends back only plain bytes (its result, serialised by the caller) through a pipe.
#include "core/error.h"

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <functional>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

namespace ff::io {

/// How an isolated call ends.
struct IsolateOptions {
  double timeout_s = 600.0;  ///< the child is killed after this long (a hang in the parser), > 0
};

/// Runs `work` in a forked child and returns the bytes it produced. In the child, fatal signals are reset to their
/// defaults (so a crash ends the child quietly, without the parent's handlers) and it leaves with _exit (no atexit
/// handlers, no leak check). Errors: Input when the child dies by a signal, exits without a whole answer, or runs
/// past `options.timeout_s` (`what` names the work in the message, e.g. "Assimp's import of bunny.obj"); Io when no
/// child can be started (fork or pipe failing). `work` itself must not throw (catch inside and encode the failure
/// in the bytes). Thread-safe in the sense fork() is: the child runs only `work`, which must not wait on locks that
/// other threads of the parent may hold (memory allocation is safe with glibc) and must not use OpenMP (GNU's
/// thread pool does not survive a fork).
Result<std::string> run_isolated(const std::function<std::string()>& work, const std::string& what,
                                 const IsolateOptions& options = {});

/// The child's answer, field by field: trivially copyable values, strings, and vectors of either (a count first).
class AnswerWriter {
 public:
  template <class T>
  void put(const T& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    out_.append(reinterpret_cast<const char*>(&v), sizeof v);
  }
  void put_string(std::string_view s) {
    put(std::uint64_t{s.size()});
    out_.append(s);
  }
  template <class T>
  void put_vector(const std::vector<T>& v) {
    put(std::uint64_t{v.size()});
    if (!v.empty()) out_.append(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(T));
  }
  std::string take() { return std::move(out_); }

 private:
  std::string out_;
};

/// `s` as one printable line: control characters (newlines, tabs …) become spaces, runs of spaces collapse, the ends
/// are trimmed, and text longer than `max_length` is cut (marked "...").
std::string one_line(std::string_view s, std::size_t max_length = 300);

/// Reading an answer back. Every read is bounds-checked, and a count is checked against the bytes left before
/// anything is allocated for it; after one failed read every later read fails too, so a caller may read a whole
/// record and test ok() once.
class AnswerReader {
 public:
  explicit AnswerReader(std::string_view in) : in_(in) {}
  template <class T>
  bool get(T& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    if (!ok_ || in_.size() < sizeof v) return ok_ = false;
    std::memcpy(&v, in_.data(), sizeof v);
    in_.remove_prefix(sizeof v);
    return true;
  }
  bool get_string(std::string& s) {
    std::uint64_t n = 0;
    if (!get(n) || n > in_.size()) return ok_ = false;
    s.assign(in_.substr(0, n));
    in_.remove_prefix(n);
    return true;
  }
  template <class T>
  bool get_vector(std::vector<T>& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    std::uint64_t n = 0;
    if (!get(n) || n > in_.size() / sizeof(T)) return ok_ = false;
    v.resize(n);
    if (n > 0) std::memcpy(v.data(), in_.data(), n * sizeof(T));
    in_.remove_prefix(n * sizeof(T));
    return true;
  }
  /// A count of records that follow, each at least `min_bytes` long (so that it cannot ask for more than came).
  bool get_count(std::uint64_t& n, std::size_t min_bytes) {
    if (!get(n) || n > in_.size() / std::max<std::size_t>(min_bytes, 1)) return ok_ = false;
    return true;
  }
  /// The rest of an answer in which the child refused the file: its error, as AnswerWriter put an Error's kind and
  /// message. Only a refusal about the file (Error::Kind::Input) whose message has something printable is one, and
  /// nothing may follow it; the message comes back as one_line. Else false (a garbled answer).
  bool get_input_error(std::string& message) {
    std::uint8_t kind = 0;
    if (!get(kind) || !get_string(message) || !at_end() || kind != static_cast<std::uint8_t>(Error::Kind::Input))
      return ok_ = false;
    message = one_line(message);
    return ok_ = !message.empty();
  }
  void fail() { ok_ = false; }
  bool ok() const { return ok_; }
  bool at_end() const { return in_.empty(); }
  std::string_view rest() const { return in_; }

 private:
  std::string_view in_;
  bool ok_ = true;
};

}  // namespace ff::io
