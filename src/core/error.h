#pragma once
// Errors are values at stage boundaries: a Result<T> holds a value or an Error.
// Only app/ turns an Error into one line on stderr and an exit code. Nothing here throws.
#include <cassert>
#include <optional>
#include <string>
#include <utility>
#include <variant>

namespace ff {

struct Error {
  enum class Kind {
    Input,      ///< bad user input: a file, a mesh, a scene value (exit code 2)
    Param,      ///< a parameter out of range or unknown (exit code 2)
    Io,         ///< the file system refused (exit code 1)
    Numerical,  ///< the simulation blew up (exit code 1)
    Cancelled,  ///< a progress hook asked to stop (exit code 1)
  };
  Kind kind = Kind::Input;
  std::string message;  ///< one line, names the thing and the reason

  /// True for errors that are the user's input or usage (exit code 2 in the CLI).
  bool is_input() const { return kind == Kind::Input || kind == Kind::Param; }
};

inline Error input_error(std::string m) { return {Error::Kind::Input, std::move(m)}; }
inline Error param_error(std::string m) { return {Error::Kind::Param, std::move(m)}; }
inline Error io_error(std::string m) { return {Error::Kind::Io, std::move(m)}; }
inline Error numerical_error(std::string m) { return {Error::Kind::Numerical, std::move(m)}; }

/// Value or Error; the interface of std::expected (C++23) in the parts we use, so it can be swapped later.
template <class T>
class [[nodiscard]] Result {
 public:
  Result(T value) : v_(std::move(value)) {}  // NOLINT(google-explicit-constructor): implicit like expected
  Result(Error error) : v_(std::move(error)) {}  // NOLINT(google-explicit-constructor)

  bool has_value() const { return v_.index() == 0; }
  explicit operator bool() const { return has_value(); }
  T& value() & { assert(has_value()); return std::get<0>(v_); }
  const T& value() const& { assert(has_value()); return std::get<0>(v_); }
  T&& value() && { assert(has_value()); return std::get<0>(std::move(v_)); }
  T& operator*() & { return value(); }
  T* operator->() { return &value(); }
  const T* operator->() const { return &value(); }
  const Error& error() const { assert(!has_value()); return std::get<1>(v_); }

 private:
  std::variant<T, Error> v_;
};

/// Result<void>: success or an Error.
class [[nodiscard]] Status {
 public:
  Status() = default;
  Status(Error error) : e_(std::move(error)) {}  // NOLINT(google-explicit-constructor)
  bool ok() const { return !e_.has_value(); }
  explicit operator bool() const { return ok(); }
  const Error& error() const { assert(e_); return *e_; }

 private:
  std::optional<Error> e_;
};

}  // namespace ff

#define FF_CONCAT_INNER(a, b) a##b
#define FF_CONCAT(a, b) FF_CONCAT_INNER(a, b)

/// Unwraps a Result into `decl` or returns its Error from the enclosing function.
#define FF_TRY(decl, expr) FF_TRY_IMPL(FF_CONCAT(ff_try_, __LINE__), decl, expr)
#define FF_TRY_IMPL(tmp, decl, expr)        \
  auto tmp = (expr);                        \
  if (!tmp.has_value()) return tmp.error(); \
  decl = std::move(tmp).value()

/// Returns the Error of a failed Status from the enclosing function.
#define FF_CHECK(expr)                                                    \
  do {                                                                    \
    if (auto ff_status_ = (expr); !ff_status_.ok()) return ff_status_.error(); \
  } while (0)
