#include "metrics/report.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <span>

namespace ff::metrics {
using nlohmann::json;

namespace {
// NaN is not JSON: metrics that are undefined are stored as null.
double num_of(const json& j) { return j.is_number() ? j.get<double>() : NAN; }
/// An integer field of a row read back; false when `j` is not an integer (a float would convert with undefined
/// behaviour when out of range).
template <class T>
bool integer(const json& j, T& out) {
  if (!j.is_number_integer()) return false;
  out = j.get<T>();
  return true;
}

}  // namespace

json json_number(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

json rows_to_json(const std::vector<FrameRow>& rows) {
  json a = json::array();
  for (const auto& r : rows)
    a.push_back({r.frame, r.time, r.particles, r.step_seconds, r.substeps, r.iterations, r.density_error_mean,
                 r.density_error_max, r.peak_memory_mib, r.controlled, json_number(r.error_rate), json_number(r.e_fwd), json_number(r.e_bwd),
                 json_number(r.e_fwd_all), json_number(r.inside), json_number(r.splash), r.control_seconds});
  return a;
}

json target_rows_to_json(const std::vector<TargetRow>& rows) {
  json a = json::array();
  for (const auto& r : rows)
    a.push_back({r.frame, r.target, r.m.fluid, r.m.controlled, json_number(r.m.error_rate), json_number(r.m.e_fwd), json_number(r.m.e_bwd),
                 json_number(r.m.e_fwd_all), json_number(r.m.inside_fraction), json_number(r.m.splash_fraction), json_number(r.m.error_spacings)});
  return a;
}

// Rows come back from a checkpoint's extra block, which resume reads leniently (pipeline/run.cpp): a row that is not an
// array of the expected length and kinds is skipped, never thrown on or read past its end.
std::vector<TargetRow> target_rows_from_json(const json& a) {
  std::vector<TargetRow> rows;
  if (!a.is_array()) return rows;
  for (const auto& e : a) {
    TargetRow r;
    if (!e.is_array() || e.size() < 11 || !integer(e[0], r.frame) || !integer(e[1], r.target) ||
        !integer(e[2], r.m.fluid) || !integer(e[3], r.m.controlled))
      continue;
    r.m.error_rate = num_of(e[4]);
    r.m.e_fwd = num_of(e[5]);
    r.m.e_bwd = num_of(e[6]);
    r.m.e_fwd_all = num_of(e[7]);
    r.m.inside_fraction = num_of(e[8]);
    r.m.splash_fraction = num_of(e[9]);
    r.m.error_spacings = num_of(e[10]);
    rows.push_back(r);
  }
  return rows;
}

std::vector<FrameRow> rows_from_json(const json& a) {
  std::vector<FrameRow> rows;
  if (!a.is_array()) return rows;
  for (const auto& e : a) {
    FrameRow r;
    if (!e.is_array() || e.size() < 9 || !integer(e[0], r.frame) || !integer(e[2], r.particles) ||
        !integer(e[4], r.substeps) || !integer(e[5], r.iterations))
      continue;
    r.time = num_of(e[1]), r.step_seconds = num_of(e[3]);
    r.density_error_mean = num_of(e[6]), r.density_error_max = num_of(e[7]), r.peak_memory_mib = num_of(e[8]);
    if (e.size() >= 16) {
      if (!integer(e[9], r.controlled)) continue;
      r.error_rate = num_of(e[10]);
      r.e_fwd = num_of(e[11]);
      r.e_bwd = num_of(e[12]);
      r.e_fwd_all = num_of(e[13]);
      r.inside = num_of(e[14]);
      r.splash = num_of(e[15]);
      if (e.size() >= 17) r.control_seconds = num_of(e[16]);
    }
    rows.push_back(r);
  }
  return rows;
}

namespace {
// The columns' names (or formats) joined by commas, one line.
std::string joined(std::span<const Column> columns, bool names) {
  std::string s;
  for (const auto& c : columns) {
    if (!s.empty()) s.push_back(',');
    s.append(names ? c.name : c.format);
  }
  s.push_back('\n');
  return s;
}
std::string header(std::span<const Column> columns) { return joined(columns, true); }
std::string row_format(std::span<const Column> columns) { return joined(columns, false); }
}  // namespace

std::string metrics_csv(const std::vector<FrameRow>& rows) {
  static const std::string format = row_format(kFrameColumns);
  std::string s = header(kFrameColumns);
  for (const auto& r : rows)
    s += fmt::format(fmt::runtime(format), r.frame, r.time, r.particles, r.step_seconds, r.substeps, r.iterations,
                     r.density_error_mean, r.density_error_max, r.peak_memory_mib, r.controlled, r.error_rate, r.e_fwd,
                     r.e_bwd, r.e_fwd_all, r.inside, r.splash, r.control_seconds);
  return s;
}

std::string target_metrics_csv(const std::vector<TargetRow>& rows) {
  static const std::string format = row_format(kTargetColumns);
  std::string s = header(kTargetColumns);
  for (const auto& r : rows)
    s += fmt::format(fmt::runtime(format), r.frame, r.target, r.m.fluid, r.m.controlled, r.m.error_rate, r.m.e_fwd,
                     r.m.e_bwd, r.m.e_fwd_all, r.m.inside_fraction, r.m.splash_fraction, r.m.error_spacings);
  return s;
}

}  // namespace ff::metrics
