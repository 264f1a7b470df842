#pragma once
// Progress/cancel hook for long operations (OpenVDB Interrupter idea).
// The CLI progress bar, the server and tests implement it; callers tick per chunk, never per particle.
#include <cstddef>
#include <string_view>

namespace ff::core {

struct Progress {
  virtual ~Progress() = default;
  virtual void begin(std::string_view /*what*/, std::size_t /*total*/) {}
  /// Reports `done` units of the total; returning false asks the operation to stop (Error::Kind::Cancelled).
  virtual bool tick(std::size_t /*done*/) { return true; }
  virtual void end() {}
};

/// A stateless do-nothing progress, shared safely.
inline Progress& null_progress() {
  static Progress p;
  return p;
}

}  // namespace ff::core
