#include "metrics/summary.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>

namespace ff::metrics {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kSteadyFraction = 0.2;  // §d.2: the last 20 % of frames
constexpr double kFormBand = 0.1;        // §d.7: within 10 % of the steady value

bool within(double value, double steady) {
  return std::isfinite(value) && std::abs(value - steady) <= kFormBand * std::abs(steady);
}

}  // namespace

FrameWindow tail_window(std::size_t frames, double fraction) {
  assert(fraction > 0.0 && fraction <= 1.0);
  if (frames == 0) return {};
  const auto count = std::clamp<std::size_t>(static_cast<std::size_t>(std::ceil(fraction * double(frames) - 1e-9)), 1, frames);
  return {frames - count, frames};
}

double window_mean(std::span<const double> values, FrameWindow window) {
  const std::size_t end = std::min(window.end, values.size());
  double sum = 0.0;
  std::size_t count = 0;
  for (std::size_t i = window.begin; i < end; ++i)
    if (std::isfinite(values[i])) {
      sum += values[i];
      ++count;
    }
  return count > 0 ? sum / double(count) : kNaN;
}

double retention_drift(std::span<const double> values, FrameWindow earlier, FrameWindow later) {
  return window_mean(values, later) - window_mean(values, earlier);
}

SeriesSummary summarize(std::span<const double> values, std::span<const double> times) {
  assert(values.size() == times.size());
  const std::size_t n = std::min(values.size(), times.size());
  values = values.first(n);
  SeriesSummary s{kNaN, kNaN, kNaN, kNaN};
  if (n == 0) return s;
  s.steady = window_mean(values, tail_window(n, kSteadyFraction));
  s.final_value = values[n - 1];
  if (!std::isfinite(s.steady)) return s;
  for (std::size_t i = 0; i < n; ++i)
    if (within(values[i], s.steady)) {
      s.time_to_form = times[i];
      break;
    }
  // Walk back from the end while the frames stay within the band.
  std::size_t first_stable = n;
  while (first_stable > 0 && within(values[first_stable - 1], s.steady)) --first_stable;
  if (first_stable < n) s.time_to_form_stable = times[first_stable];
  return s;
}

double formed_since(std::span<const double> inside, std::span<const double> splash, std::span<const double> times,
                    const FormedThresholds& th) {
  const std::size_t n = std::min({inside.size(), splash.size(), times.size()});
  // Walk back from the end while the frames are formed.
  std::size_t first = n;
  while (first > 0 && is_formed(inside[first - 1], splash[first - 1], th)) --first;
  return first < n ? times[first] : kNaN;
}

bool formed_held(std::span<const double> inside, std::span<const double> splash, std::span<const double> times,
                 const FormedThresholds& th) {
  const std::size_t n = std::min({inside.size(), splash.size(), times.size()});
  if (n == 0) return false;
  for (std::size_t i = n; i-- > 0;) {
    if (!is_formed(inside[i], splash[i], th)) return false;
    if (times[n - 1] - times[i] >= th.hold_s - 1e-9) return true;
  }
  return false;
}

}  // namespace ff::metrics
