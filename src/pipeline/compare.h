#pragma once
// `fluidform compare`: every controller on one scene, the paper's Table 3 columns (METHOD §d) side by side.
// Each controller runs as a child process of the same binary (`fluidform run`), so its peak memory is its own
// and a crash or blow-up of one controller costs only its row.
#include "core/error.h"

#include <nlohmann/json_fwd.hpp>

#include <cmath>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace ff::pipeline {

struct CompareOptions {
  std::filesystem::path scene_file;
  std::filesystem::path out_dir = "fluidform-compare";
  std::vector<std::string> controllers;  ///< empty: every registered controller, in registry order
  std::optional<int> frames;             ///< default: the scene's output.frames if it sets it, else kDefaultFrames
  std::filesystem::path exe;             ///< the fluidform binary; empty: /proc/self/exe
  std::optional<double> max_memory_mib;  ///< --max-memory: overrides scene.limits.max_memory_mb, for every run
  std::string device = "cpu";            ///< --device, for every run (gpu: only controllers the GPU path has)
};

/// Run length when neither --frames nor the scene's output.frames says: 5 s at 60 fps. A scene without
/// output.frames normally runs "until formed", which would give every controller a different length.
inline constexpr int kDefaultCompareFrames = 300;

/// One controller's row. Numbers that are unknown (a run that failed before measuring them) are NaN.
struct CompareRow {
  std::string controller;
  bool approximation = false;  ///< the registry's flag: marked "[A]"
  bool ok = false;             ///< formed and did not fail
  std::string status;          ///< "ok", "failure (blew up: ...)", "failure (never formed)"
  double particles = NAN, control_particles = NAN, controlled = NAN, controlled_per_control = NAN;
  double error_rate_pct = NAN, error_rate_final_pct = NAN, frame_seconds = NAN, memory_mb = NAN;
  double splash_pct = NAN, inside_pct = NAN, time_to_form_s = NAN, time_to_settle_s = NAN, retention_pp = NAN;
  double error_spacings = NAN, e_fwd_all_m = NAN;
  double wall_seconds = NAN;  ///< the child's whole run (sampling, I/O included), for planning benchmark time
};

struct CompareTable {
  std::string scene;  ///< the scene file's stem
  std::string scene_file;
  int frames = 0;
  double fps = 60.0;
  double particles = NAN;  ///< fluid particles (from the first run that reported them)
  int threads = 0;
  std::string cpu;
  std::string device = "cpu";  ///< --device the runs were given (each run's report.json names what ran)
  std::vector<CompareRow> rows;
};

/// Runs every controller of `options` on the scene, one child process each, into OUT/NAME/, and writes
/// OUT/table.md, OUT/table.csv and OUT/table.json (after every controller, so a killed compare leaves the rows so
/// far). Errors: an unreadable scene, an unknown controller (before anything is written), an unwritable OUT.
/// A controller that fails is a row with a failure status, not an error.
Result<CompareTable> run_compare(const CompareOptions& options);

/// "a,b,c" → names, each checked against the registry (a Param error names the first unknown one); duplicates
/// are dropped. An empty list is an error.
Result<std::vector<std::string>> parse_controller_list(std::string_view list);

/// The registered controllers for --help: one line each, "[A]" on approximations, and what [A] means.
std::string controllers_help();

/// The header line and the Markdown table (DESIGN: the paper's columns plus splash, inside, time to form,
/// retention, status).
std::string table_markdown(const CompareTable& table);
/// One row's Markdown cells, in the order of markdown_columns() (for tables that add columns, e.g. bench_table3).
std::vector<std::string> markdown_cells(const CompareRow& row);
const std::vector<std::string>& markdown_columns();
std::string table_csv(const CompareTable& table);
nlohmann::json table_to_json(const CompareTable& table);
Result<CompareTable> table_from_json(const nlohmann::json& j);

/// How a child process ended.
struct ChildExit {
  int code = -1;    ///< exit status, or -1 when killed by a signal
  int signal = 0;   ///< the signal that killed it, else 0
  bool ok() const { return code == 0; }
  std::string describe() const;  ///< "exit code 3", "killed by signal 11 (Segmentation fault)"
};

/// Runs `argv` (argv[0] is the program's path; no shell) and waits. stdout and stderr go to the given files,
/// or are inherited when empty; `stdout_to_stderr` sends stdout to the (inherited) stderr instead.
Result<ChildExit> run_child(const std::vector<std::string>& argv, const std::filesystem::path& stdout_file = {},
                            const std::filesystem::path& stderr_file = {}, bool stdout_to_stderr = false);

/// "model name" of /proc/cpuinfo ("unknown CPU" when not there).
std::string cpu_model();

}  // namespace ff::pipeline
