#pragma once
// The per-frame report of a run: metrics.csv (one row per frame: solver statistics and the shape metrics of METHOD
// §d), metrics_targets.csv (each target's own metrics per frame), and the rows' JSON form kept in a checkpoint so a
// resumed run writes the whole table. The column names are listed once, here: the writer and every reader
// (`compare`, the server's playback) use these constants.
#include "metrics/shape_metrics.h"

#include <nlohmann/json_fwd.hpp>

#include <array>
#include <cmath>
#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

namespace ff::metrics {

/// A CSV column: its name in the header and the fmt format of its values.
struct Column {
  std::string_view name, format;
};

/// The names readers look columns up by.
namespace column {
inline constexpr std::string_view frame = "frame", time = "time_s", step_time = "step_time_s",
                                  error_rate = "error_rate_pct";
}  // namespace column

/// metrics.csv, in order (FrameRow's fields).
inline constexpr std::array<Column, 17> kFrameColumns{{
    {column::frame, "{}"}, {column::time, "{:.6f}"}, {"particles", "{}"}, {column::step_time, "{:.6f}"},
    {"substeps", "{}"}, {"iterations", "{}"}, {"density_error_mean", "{:.6g}"}, {"density_error_max", "{:.6g}"},
    {"peak_memory_mb", "{:.1f}"}, {"controlled", "{}"}, {column::error_rate, "{:.6g}"}, {"e_fwd_m", "{:.6g}"},
    {"e_bwd_m", "{:.6g}"}, {"e_fwd_all_m", "{:.6g}"}, {"inside_fraction", "{:.6g}"}, {"splash_fraction", "{:.6g}"},
    {"control_time_s", "{:.6f}"},
}};
/// metrics_targets.csv, in order (TargetRow's fields).
inline constexpr std::array<Column, 11> kTargetColumns{{
    {column::frame, "{}"}, {"target", "{}"}, {"fluid", "{}"}, {"controlled", "{}"}, {column::error_rate, "{:.6g}"},
    {"e_fwd_m", "{:.6g}"}, {"e_bwd_m", "{:.6g}"}, {"e_fwd_all_m", "{:.6g}"}, {"inside_fraction", "{:.6g}"},
    {"splash_fraction", "{:.6g}"}, {"error_spacings", "{:.6g}"},
}};

/// One row of metrics.csv (docs/outputs.md), its columns in kFrameColumns.
struct FrameRow {
  int frame = 0;
  double time = 0.0;              // s, simulated time at the end of the frame
  std::size_t particles = 0;
  double step_seconds = 0.0;      // wall-clock of the frame's sub-steps (no I/O)
  int substeps = 0;
  long iterations = 0;            // density-constraint sweeps over all sub-steps
  double density_error_mean = 0;  // mean of max(ρ/ρ0 − 1, 0)
  double density_error_max = 0;
  double peak_memory_mib = 0;
  // Shape metrics (METHOD §d), N_c-weighted over the targets; NaN without targets.
  std::size_t controlled = 0;
  double error_rate = NAN, e_fwd = NAN, e_bwd = NAN, e_fwd_all = NAN, inside = NAN, splash = NAN;
  double control_seconds = 0;     // wall-clock of the controller's hooks within step_seconds
};

/// One target's metrics in one frame (metrics_targets.csv).
struct TargetRow {
  int frame = 0;
  int target = 0;
  metrics::FrameMetrics m;
};

/// NaN is not JSON: an undefined metric is stored as null.
nlohmann::json json_number(double v);
std::string metrics_csv(const std::vector<FrameRow>& rows);
std::string target_metrics_csv(const std::vector<TargetRow>& rows);
/// The rows as JSON arrays (a checkpoint's "rows" / "target_rows"; NaN as null) and back (a row that is not such an
/// array is skipped; never throws).
nlohmann::json rows_to_json(const std::vector<FrameRow>& rows);
std::vector<FrameRow> rows_from_json(const nlohmann::json& a);
nlohmann::json target_rows_to_json(const std::vector<TargetRow>& rows);
std::vector<TargetRow> target_rows_from_json(const nlohmann::json& a);

}  // namespace ff::metrics
