#include "app/progress_bar.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <unistd.h>

namespace ff::app {

ProgressBar::ProgressBar(std::FILE* out, int interactive)
    : out_(out), tty_(interactive >= 0 ? interactive != 0 : ::isatty(::fileno(out)) != 0) {}

void ProgressBar::begin(std::string_view what, std::size_t total) {
  what_ = what;
  total_ = total;
  last_decile_ = -1;
  first_tick_ = true;
  watch_.restart();
  last_draw_ = -1.0;
}

bool ProgressBar::tick(std::size_t done) {
  if (first_tick_) {
    begin_done_ = done;  // a resumed run starts part-way: the ETA counts only this session's rate
    first_tick_ = false;
  }
  const double frac = total_ ? double(done) / double(total_) : 1.0;
  const double t = watch_.seconds();
  const double rate = t > 0 ? double(done - begin_done_) / t : 0.0;
  const double eta = rate > 0 ? double(total_ - done) / rate : 0.0;
  if (tty_) {
    if (t - last_draw_ < 0.1 && done < total_) return true;  // redraw at most 10 times a second
    last_draw_ = t;
    constexpr int kWidth = 30;
    const int filled = static_cast<int>(frac * kWidth);
    fmt::print(out_, "\r{} [{}{}] {}/{} {} ETA {:.0f}s \x1b[K", what_, std::string(filled, '#'),
               std::string(kWidth - filled, ' '), done, total_, status_, eta);
    std::fflush(out_);
  } else {
    const int decile = static_cast<int>(frac * 10.0);
    if (decile != last_decile_) {
      last_decile_ = decile;
      spdlog::info("{}: {}/{} ({:.0f}%) {} ETA {:.0f}s", what_, done, total_, 100.0 * frac, status_, eta);
    }
  }
  return true;
}

void ProgressBar::end() {
  if (tty_) {
    fmt::print(out_, "\n");
    std::fflush(out_);
  }
}

}  // namespace ff::app
