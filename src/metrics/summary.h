#pragma once
// Run-level numbers from a per-frame series of the error rate E(t) (METHOD.md §d.2, §d.5, §d.7).
//
// Frames where E is undefined (NaN: no fluid of the target yet) are left out of every mean and are never
// "within" a band; a series with no finite value gives NaN everywhere.
#include <cstddef>
#include <span>

namespace ff::metrics {

/// Frames [begin, end) of a series.
struct FrameWindow {
  std::size_t begin = 0;
  std::size_t end = 0;
};

/// The last `fraction` of `frames` frames (at least one frame when frames > 0). fraction in (0, 1].
FrameWindow tail_window(std::size_t frames, double fraction);

/// Mean of the finite values in `window` (clamped to the series); NaN when there are none.
double window_mean(std::span<const double> values, FrameWindow window);

/// Shape retention (§d.5): mean E over `later` minus mean E over `earlier` (positive = the shape degrades).
/// Typical use: earlier = the frames just after forming, later = tail_window(n, 0.05) of a 10× longer run.
double retention_drift(std::span<const double> values, FrameWindow earlier, FrameWindow later);

struct SeriesSummary {
  double steady = 0;       ///< mean E over the last 20 % of frames (the reported number, §d.2)
  double final_value = 0;  ///< E at the last frame (NaN when undefined there)
  /// First time E(t) is within 10 % of `steady` (|E − steady| ≤ 0.1·|steady|), §d.7. When E starts low
  /// (the fluid starts on the target) this is the first frame; NaN when never within.
  double time_to_form = 0;
  /// First time after which E stays within 10 % of `steady` to the end (stricter: a shape that forms, then
  /// collapses and forms again counts from the second forming). NaN when the last frame is not within.
  double time_to_form_stable = 0;
};

/// Summary of `values` (E per frame, %) at `times` (s of simulated time; same length, increasing).
SeriesSummary summarize(std::span<const double> values, std::span<const double> times);

/// When a shape counts as formed: at least `min_inside` of the fluid inside its target and at most `max_splash` of it
/// splashed (fractions, the floor of bench/RESULTS.md's quality table), held for `hold_s` seconds of simulated time.
struct FormedThresholds {
  double min_inside = 0.99;
  double max_splash = 0.005;
  double hold_s = 1.0;
};
inline bool is_formed(double inside, double splash, const FormedThresholds& th) {
  return inside >= th.min_inside && splash <= th.max_splash;  // false for NaN
}

/// The first time from which the shape stays formed (`is_formed` at every frame) to the end of the run; NaN when the
/// last frame is not formed. A shape that forms, lets go and forms again counts from the last forming. (th.hold_s is
/// the stop rule's, formed_held's.)
double formed_since(std::span<const double> inside, std::span<const double> splash, std::span<const double> times,
                    const FormedThresholds& th = {});

/// Whether the frames of the last th.hold_s seconds, from one at least th.hold_s before the last frame, are all
/// formed (the stop rule of a run without --frames).
bool formed_held(std::span<const double> inside, std::span<const double> splash, std::span<const double> times,
                 const FormedThresholds& th = {});

}  // namespace ff::metrics
