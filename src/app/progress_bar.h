#pragma once
// The CLI's core::Progress: a redrawn bar on a terminal, plain log lines (about every 10 %) otherwise.
#include "core/progress.h"
#include "core/timer.h"

#include <cstdio>
#include <string>

namespace ff::app {

class ProgressBar final : public core::Progress {
 public:
  /// `out` is where the bar goes (stderr); `interactive` forces the mode (default: isatty(out)).
  explicit ProgressBar(std::FILE* out = stderr, int interactive = -1);
  void begin(std::string_view what, std::size_t total) override;
  bool tick(std::size_t done) override;
  void end() override;
  /// Extra text shown after the counter (e.g. "4.1 ms/frame").
  void set_status(std::string s) { status_ = std::move(s); }

 private:
  std::FILE* out_;
  bool tty_;
  std::string what_, status_;
  std::size_t total_ = 0, begin_done_ = 0;
  int last_decile_ = -1;
  bool first_tick_ = true;
  core::Stopwatch watch_;
  double last_draw_ = -1.0;
};

}  // namespace ff::app
