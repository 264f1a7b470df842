#include "pipeline/compare.h"
#include "pipeline/compare_page.h"

#include "pipeline/stepper.h"

#include "pipeline/auto_scene.h"
#include "pipeline/run_budget.h"

#include "metrics/report.h"

#include "control/registry.h"
#include "core/parallel.h"
#include "io/atomic_file.h"
#include "io/csv_table.h"
#include "io/load_mesh.h"
#include "scene/scene.h"
#include "metrics/summary.h"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <sstream>

extern char** environ;

namespace ff::pipeline {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr double kNeverFormedPct = 50.0;  // the paper's "failure": a steady error above this never formed the shape
constexpr double kRetentionWindow = 0.1;  // retention compares two windows of 10 % of the run's frames
constexpr std::size_t kMaxReason = 160;   // a failure reason stays one readable table cell

std::string read_text(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}

// One line of at most kMaxReason characters; '|' would split a Markdown cell.
std::string one_line(std::string s) {
  for (char& c : s)
    if (c == '\n' || c == '\r' || c == '|') c = ' ';
  const auto first = s.find_first_not_of(' '), last = s.find_last_not_of(' ');
  s = first == std::string::npos ? std::string() : s.substr(first, last - first + 1);
  if (s.size() > kMaxReason) s = s.substr(0, kMaxReason - 3) + "...";
  return s;
}

// The last non-empty line a child wrote to `log`, without the CLI's "fluidform: error: " prefix.
std::string last_log_line(const fs::path& log) {
  std::istringstream in(read_text(log));
  std::string line, last;
  while (std::getline(in, line))
    if (line.find_first_not_of(" \t\r") != std::string::npos) last = line;
  constexpr std::string_view kPrefix = "fluidform: error: ";
  if (last.rfind(kPrefix, 0) == 0) last = last.substr(kPrefix.size());
  return one_line(last);
}

double number(const json& obj, const char* key) {
  return obj.is_object() && obj.contains(key) && obj[key].is_number() ? obj[key].get<double>() : NAN;
}

json num_json(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

// E(t) of a run, from its metrics.csv (time_s and error_rate_pct columns; "nan" reads as NaN).
struct ErrorSeries {
  std::vector<double> time, error;
};

ErrorSeries read_error_series(const fs::path& csv) {
  ErrorSeries s;
  const io::CsvTable t = io::read_csv(csv);
  const std::size_t c_time = t.column(metrics::column::time), c_err = t.column(metrics::column::error_rate);
  if (c_time >= t.head.size() || c_err >= t.head.size()) return s;
  for (const auto& f : t.rows) {
    if (f.size() <= std::max(c_time, c_err)) continue;
    s.time.push_back(std::strtod(f[c_time].c_str(), nullptr));
    s.error.push_back(std::strtod(f[c_err].c_str(), nullptr));
  }
  return s;
}

// Retention (METHOD §d.5 on a run of fixed length): mean E over the last 10 % of frames minus mean E over the
// 10 %-of-run window that starts when E settled (report.json time_to_settle_s). NaN when it never settled or the
// windows overlap (the run ends too soon after settling to tell drift from forming).
double retention_pp(const ErrorSeries& s, double time_to_form) {
  const std::size_t n = s.error.size();
  if (n == 0 || !std::isfinite(time_to_form)) return NAN;
  const metrics::FrameWindow later = metrics::tail_window(n, kRetentionWindow);
  std::size_t begin = 0;
  while (begin < n && s.time[begin] < time_to_form - 1e-9) ++begin;
  const metrics::FrameWindow earlier{begin, begin + (later.end - later.begin)};
  if (earlier.end > later.begin) return NAN;
  return metrics::retention_drift(s.error, earlier, later);
}

void fill_from_totals(const json& t, CompareRow& row) {
  row.particles = number(t, "particles");
  row.control_particles = number(t, "control_particles");
  row.controlled = number(t, "controlled_final");
  row.controlled_per_control = number(t, "controlled_per_control");
  row.error_rate_pct = number(t, "error_rate_pct");
  row.error_rate_final_pct = number(t, "error_rate_final_pct");
  row.frame_seconds = number(t, "mean_step_time_s");
  row.memory_mb = number(t, "peak_memory_mb");
  row.splash_pct = 100.0 * number(t, "splash_fraction");
  row.inside_pct = 100.0 * number(t, "inside_fraction");
  row.time_to_form_s = number(t, "time_to_form_s");
  row.time_to_settle_s = number(t, "time_to_settle_s");
  row.error_spacings = number(t, "error_spacings");
  row.e_fwd_all_m = number(t, "e_fwd_all_m");
}

// Why a run failed, in one line: the report's error, else the child's last stderr line, else how it ended.
std::string blow_up_reason(const ChildExit& ended, const json& report, const fs::path& log) {
  if (report.is_object() && report.contains("error") && report["error"].is_string())
    return one_line(report["error"].get<std::string>());
  if (const std::string line = last_log_line(log); !line.empty() && !ended.ok()) return line;
  if (!ended.ok()) return ended.describe();
  if (!report.is_object()) return "no report.json";
  return one_line(fmt::format("report status \"{}\"", report.value("status", std::string("?"))));
}

struct RunSetup {
  fs::path exe, scene;
  int frames = 0;
  std::optional<double> max_memory_mib;  // passed on to every run
  std::string device;                    // passed on to every run
  io::PictureView view;                  // of every formed shape's picture (compare_view of the targets)
};

// The run's final mesh as OUT/NAME/formed.png, for compare.html (a run without one is shown without a picture).
void picture_formed(const fs::path& dir, const io::PictureView& view) {
  if (!fs::is_regular_file(dir / "mesh" / "final.obj")) return;
  auto mesh = io::load_mesh(dir / "mesh" / "final.obj");
  const Status st = mesh ? write_still(dir / "formed.png", *mesh, view, false) : Status(mesh.error());
  if (!st.ok()) spdlog::warn("compare: no picture of {}'s formed shape: {}", dir.filename().string(), st.error().message);
}

// Runs one controller in its own process into `dir` and reads its row from report.json and metrics.csv.
Result<CompareRow> run_controller(const RunSetup& setup, const control::ControllerInfo& entry, const fs::path& dir) {
  CompareRow row;
  row.controller = std::string(entry.name);
  row.approximation = entry.approximation;
  // A clean folder: a report left by an earlier compare must never be read as this run's.
  std::error_code ec;
  fs::remove_all(dir, ec);
  if (ec) return io_error(fmt::format("{}: cannot clear: {}", dir.string(), ec.message()));
  FF_CHECK(io::ensure_writable_dir(dir));
  std::vector<std::string> argv{setup.exe.string(), "-q", "run", setup.scene.string(), "--controller",
                                      row.controller, "-o", dir.string(), "--no-animation", "--frames",
                                      std::to_string(setup.frames)};
  if (setup.max_memory_mib) argv.insert(argv.end(), {"--max-memory", fmt::format("{}", *setup.max_memory_mib)});
  argv.insert(argv.end(), {"--device", setup.device});
  const auto start = std::chrono::steady_clock::now();
  FF_TRY(const ChildExit ended, run_child(argv, "/dev/null", dir / "stderr.log"));
  row.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  const json report = json::parse(read_text(dir / "report.json"), nullptr, false);
  if (report.is_object() && report.contains("totals")) fill_from_totals(report["totals"], row);
  const bool reported_ok = report.is_object() && report.value("status", std::string()) == "ok";
  // report.json says "ok" once the frames are simulated and measured; what the run does after (meshing its final
  // frame for the picture) failing costs the picture, not the row.
  if (reported_ok && !ended.ok())
    spdlog::warn("compare: {} simulated, then its run ended with {} (no picture of its formed shape)", row.controller,
                 ended.describe());
  if (!reported_ok) {
    row.status = "failure (blew up: " + blow_up_reason(ended, report, dir / "stderr.log") + ")";
  } else if (!(row.error_rate_pct <= kNeverFormedPct)) {  // NaN too
    row.status = "failure (never formed)";
  } else {
    row.ok = true;
    row.status = "ok";
    // Drift from when E settled (a baseline that never keeps 99 % inside still has a drift to compare).
    row.retention_pp = retention_pp(read_error_series(dir / "metrics.csv"), row.time_to_settle_s);
  }
  picture_formed(dir, setup.view);
  // The particle frames (GBs at 250k particles over 300 frames) and checkpoints are not part of the table.
  fs::remove_all(dir / "particles", ec);
  fs::remove_all(dir / "checkpoint", ec);
  return row;
}

Result<std::vector<const control::ControllerInfo*>> resolve_controllers(const std::vector<std::string>& names) {
  std::vector<const control::ControllerInfo*> out;
  if (names.empty()) {
    for (const auto& e : control::registry()) out.push_back(&e);
    return out;
  }
  for (const auto& n : names) {
    const auto* e = control::find_controller(n);
    if (!e) return param_error(fmt::format("--controllers: \"{}\" is not one of: {}", n, control::controller_names()));
    if (std::find(out.begin(), out.end(), e) == out.end()) out.push_back(e);
  }
  return out;
}

Result<fs::path> resolve_exe(const fs::path& given) {
  std::error_code ec;
  const fs::path exe = given.empty() ? fs::read_symlink("/proc/self/exe", ec) : given;
  if (ec || !fs::exists(exe, ec))
    return io_error(fmt::format("cannot find the fluidform binary{}", given.empty() ? "" : ": " + given.string()));
  return exe;
}

// A missing mesh would fail every controller the same way: bad input, refused before anything runs.
Status check_meshes(const scene::Scene& scene) {
  std::error_code ec;
  for (std::size_t i = 0; i < scene.targets.size(); ++i) {
    std::vector<fs::path> meshes{scene.targets[i].mesh};
    for (const auto& sw : scene.targets[i].swaps) meshes.push_back(sw.mesh);
    for (const auto& m : meshes)
      if (!fs::is_regular_file(m, ec)) return input_error(fmt::format("targets[{}]: {}: no such file", i, m.string()));
  }
  return {};
}

Status write_tables(const fs::path& dir, const CompareTable& table) {
  FF_CHECK(io::write_file_atomic(dir / "table.md", table_markdown(table)));
  FF_CHECK(write_compare_page(dir, table));
  FF_CHECK(io::write_file_atomic(dir / "table.csv", table_csv(table)));
  return io::write_file_atomic(dir / "table.json", table_to_json(table).dump(2) + "\n");
}

std::string fixed(double v, int digits) { return std::isfinite(v) ? fmt::format("{:.{}f}", v, digits) : "n/a"; }

// CSV: a number with enough digits to compare runs, or empty when unknown; text quoted when it needs it.
std::string csv_num(double v) { return std::isfinite(v) ? fmt::format("{:.6g}", v) : ""; }
std::string csv_text(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string q = "\"";
  for (char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

}  // namespace

std::string ChildExit::describe() const {
  if (signal != 0) return fmt::format("killed by signal {} ({})", signal, strsignal(signal));
  return fmt::format("exit code {}", code);
}

Result<ChildExit> run_child(const std::vector<std::string>& argv, const fs::path& stdout_file, const fs::path& stderr_file,
                            bool stdout_to_stderr) {
  if (argv.empty()) return param_error("run_child: no program given");
  std::vector<std::string> args = argv;
  std::vector<char*> cargv;
  for (auto& a : args) cargv.push_back(a.data());
  cargv.push_back(nullptr);
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  if (!stdout_file.empty())
    posix_spawn_file_actions_addopen(&fa, 1, stdout_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  else if (stdout_to_stderr)
    posix_spawn_file_actions_adddup2(&fa, 2, 1);
  if (!stderr_file.empty())
    posix_spawn_file_actions_addopen(&fa, 2, stderr_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  pid_t pid = -1;
  const int rc = posix_spawn(&pid, cargv[0], &fa, nullptr, cargv.data(), environ);
  posix_spawn_file_actions_destroy(&fa);
  if (rc != 0) return io_error(fmt::format("{}: cannot start: {}", argv[0], std::strerror(rc)));
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0)
    if (errno != EINTR) return io_error(fmt::format("{}: cannot wait for it: {}", argv[0], std::strerror(errno)));
  ChildExit e;
  if (WIFEXITED(status)) e.code = WEXITSTATUS(status);
  else if (WIFSIGNALED(status)) e.signal = WTERMSIG(status);
  return e;
}

std::string cpu_model() {
  std::istringstream in(read_text("/proc/cpuinfo"));
  for (std::string line; std::getline(in, line);)
    if (line.rfind("model name", 0) == 0 && line.find(':') != std::string::npos) return one_line(line.substr(line.find(':') + 1));
  return "unknown CPU";
}

Result<std::vector<std::string>> parse_controller_list(std::string_view list) {
  std::vector<std::string> names;
  for (const auto& item : io::split_fields(std::string(list), ',')) {
    const std::string name = one_line(item);
    if (name.empty()) return param_error(fmt::format("--controllers \"{}\": an empty name", list));
    if (!control::find_controller(name))
      return param_error(fmt::format("--controllers: \"{}\" is not one of: {}", name, control::controller_names()));
    if (std::find(names.begin(), names.end(), name) == names.end()) names.push_back(name);
  }
  if (names.empty()) return param_error("--controllers: no controller named");
  return names;
}

std::string controllers_help() {
  std::string s = "Controllers ([A]: an approximation of a method whose details are not public, METHOD.md §b):\n";
  for (const auto& e : control::registry())
    s += fmt::format("  {:<14} {}\n", std::string(e.name) + (e.approximation ? " [A]" : ""), e.summary);
  return s;
}

const std::vector<std::string>& markdown_columns() {
  static const std::vector<std::string> kColumns{
      "controller",    "controlled / fluid particles", "controlled / control", "error rate (%)", "per-frame time (s)",
      "memory (MB)",   "splash (%)",           "inside (%)",           "time to form (s)", "retention (pp)",
      "status"};
  return kColumns;
}

std::vector<std::string> markdown_cells(const CompareRow& r) {
  return {r.controller + (r.approximation ? " [A]" : ""),
          // The fluid count is per row: lcat adds temporary particles during the run.
          std::isfinite(r.controlled) ? fixed(r.controlled, 0) + " / " + fixed(r.particles, 0) : "n/a",
          fixed(r.controlled_per_control, 2),
          r.ok ? fixed(r.error_rate_pct, 3) : "failure",
          fixed(r.frame_seconds, 4),
          fixed(r.memory_mb, 0),
          fixed(r.splash_pct, 2),
          fixed(r.inside_pct, 1),
          fixed(r.time_to_form_s, 2),
          std::isfinite(r.retention_pp) ? fmt::format("{:+.3f}", r.retention_pp) : "n/a",
          r.status};
}

std::string table_markdown(const CompareTable& t) {
  std::string s = fmt::format("**{}** ({}): {} particles, {} frames ({:.2f} s simulated), {} threads, {}{}\n\n", t.scene,
                              t.scene_file, fixed(t.particles, 0), t.frames, t.frames / t.fps, t.threads, t.cpu,
                              t.device == "cpu" ? "" : ", --device " + t.device);
  const auto& cols = markdown_columns();
  s += "| " + fmt::format("{}", fmt::join(cols, " | ")) + " |\n|";
  for (std::size_t i = 0; i < cols.size(); ++i) s += i == 0 ? "---|" : "---:|";
  s += "\n";
  bool any_approx = false;
  for (const auto& r : t.rows) {
    s += "| " + fmt::format("{}", fmt::join(markdown_cells(r), " | ")) + " |\n";
    any_approx = any_approx || r.approximation;
  }
  if (any_approx) s += "\n[A]: an approximation of a method whose details are not public (METHOD.md §b).\n";
  return s;
}

std::string table_csv(const CompareTable& t) {
  std::string s =
      "scene,controller,approximation,status,particles,control_particles,controlled_particles,controlled_per_control,"
      "error_rate_pct,error_rate_final_pct,error_spacings,per_frame_time_s,memory_mb,splash_pct,inside_pct,"
      "e_fwd_all_m,time_to_form_s,retention_pp,wall_s\n";
  for (const auto& r : t.rows)
    s += fmt::format("{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}\n", csv_text(t.scene),
                     csv_text(r.controller), r.approximation ? 1 : 0, csv_text(r.status), csv_num(r.particles),
                     csv_num(r.control_particles), csv_num(r.controlled), csv_num(r.controlled_per_control),
                     r.ok ? csv_num(r.error_rate_pct) : "failure", csv_num(r.error_rate_final_pct),
                     csv_num(r.error_spacings), csv_num(r.frame_seconds), csv_num(r.memory_mb), csv_num(r.splash_pct),
                     csv_num(r.inside_pct), csv_num(r.e_fwd_all_m), csv_num(r.time_to_form_s), csv_num(r.retention_pp),
                     csv_num(r.wall_seconds));
  return s;
}

json table_to_json(const CompareTable& t) {
  json rows = json::array();
  for (const auto& r : t.rows)
    rows.push_back({{"controller", r.controller},
                    {"approximation", r.approximation},
                    {"ok", r.ok},
                    {"status", r.status},
                    {"particles", num_json(r.particles)},
                    {"control_particles", num_json(r.control_particles)},
                    {"controlled", num_json(r.controlled)},
                    {"controlled_per_control", num_json(r.controlled_per_control)},
                    {"error_rate_pct", num_json(r.error_rate_pct)},
                    {"error_rate_final_pct", num_json(r.error_rate_final_pct)},
                    {"per_frame_time_s", num_json(r.frame_seconds)},
                    {"memory_mb", num_json(r.memory_mb)},
                    {"splash_pct", num_json(r.splash_pct)},
                    {"inside_pct", num_json(r.inside_pct)},
                    {"time_to_form_s", num_json(r.time_to_form_s)},
                    {"retention_pp", num_json(r.retention_pp)},
                    {"error_spacings", num_json(r.error_spacings)},
                    {"e_fwd_all_m", num_json(r.e_fwd_all_m)},
                    {"wall_s", num_json(r.wall_seconds)}});
  return {{"scene", t.scene}, {"scene_file", t.scene_file}, {"frames", t.frames}, {"fps", t.fps},
          {"particles", num_json(t.particles)}, {"threads", t.threads}, {"cpu", t.cpu}, {"device", t.device}, {"rows", rows}};
}

Result<CompareTable> table_from_json(const json& j) {
  if (!j.is_object() || !j.contains("rows") || !j["rows"].is_array()) return input_error("not a compare table");
  CompareTable t;
  t.scene = j.value("scene", std::string());
  t.scene_file = j.value("scene_file", std::string());
  t.frames = j.value("frames", 0);
  t.fps = number(j, "fps");
  t.particles = number(j, "particles");
  t.threads = j.value("threads", 0);
  t.cpu = j.value("cpu", std::string());
  t.device = j.value("device", std::string("cpu"));
  for (const auto& e : j["rows"]) {
    if (!e.is_object()) return input_error("a compare table row is not an object");
    CompareRow r;
    r.controller = e.value("controller", std::string());
    r.approximation = e.value("approximation", false);
    r.ok = e.value("ok", false);
    r.status = e.value("status", std::string());
    r.particles = number(e, "particles");
    r.control_particles = number(e, "control_particles");
    r.controlled = number(e, "controlled");
    r.controlled_per_control = number(e, "controlled_per_control");
    r.error_rate_pct = number(e, "error_rate_pct");
    r.error_rate_final_pct = number(e, "error_rate_final_pct");
    r.frame_seconds = number(e, "per_frame_time_s");
    r.memory_mb = number(e, "memory_mb");
    r.splash_pct = number(e, "splash_pct");
    r.inside_pct = number(e, "inside_pct");
    r.time_to_form_s = number(e, "time_to_form_s");
    r.retention_pp = number(e, "retention_pp");
    r.error_spacings = number(e, "error_spacings");
    r.e_fwd_all_m = number(e, "e_fwd_all_m");
    r.wall_seconds = number(e, "wall_s");
    t.rows.push_back(std::move(r));
  }
  return t;
}

Result<CompareTable> run_compare(const CompareOptions& o) {
  // Everything is checked before the output folder is touched.
  FF_TRY(const auto entries, resolve_controllers(o.controllers));
  FF_TRY(const Device device, parse_device(o.device));
  FF_TRY(const scene::Scene scene, scene::load_scene(o.scene_file));
  for (const auto* e : entries) {  // --device gpu with a controller the GPU path does not have: one line, up front
    control::ControllerSpec spec = scene.controller;
    spec.name = std::string(e->name);
    FF_CHECK(check_device(device, spec));
  }
  if (scene.targets.empty())
    return input_error(fmt::format("{}: the scene has no targets, so there is no shape to compare controllers on",
                                   o.scene_file.string()));
  FF_CHECK(check_meshes(scene));
  io::TriangleMesh targets;  // every target at its scene transform, for the pictures
  {
    // The memory one run will need (each controller runs alone), checked as `run` checks it: a scene too large for
    // the machine fails here with one line, not once per controller after the others have run.
    FF_TRY(auto geometry, load_target_meshes(scene));
    for (const auto& g : geometry) {
      const auto off = static_cast<Index>(targets.vertices.size());
      targets.vertices.insert(targets.vertices.end(), g.mesh.vertices.begin(), g.mesh.vertices.end());
      for (const auto& tri : g.mesh.triangles) targets.triangles.push_back({tri[0] + off, tri[1] + off, tri[2] + off});
    }
    scene::Scene completed = scene;
    FF_CHECK(complete_scene(completed, geometry));
    FF_TRY(const RunEstimate estimate, check_run_budget(completed, geometry, o.max_memory_mib));
    if (estimate.large)
      spdlog::warn("a large scene: about {} fluid particles and {} control samples, ~{:.0f} MiB per run (limit {:.0f} "
                   "MiB)", estimate.fluid_particles, estimate.control_samples, estimate.memory_mib, estimate.limit_mib);
  }
  // Every controller runs the same length: "until formed" would stop each at a different frame.
  const int frames = o.frames.value_or(scene.auto_frames ? kDefaultCompareFrames : scene.output.frames);
  if (!(frames >= 1 && frames <= 10'000'000)) return param_error(fmt::format("--frames = {} is outside [1, 10000000]", frames));
  FF_TRY(const fs::path exe, resolve_exe(o.exe));
  FF_CHECK(io::ensure_writable_dir(o.out_dir));
  if (const auto n = io::remove_stale_temp_files(o.out_dir))
    spdlog::info("compare: removed {} partial file(s) an interrupted compare left", n);

  CompareTable table;
  table.scene = o.scene_file.stem().string();
  table.scene_file = o.scene_file.string();
  table.frames = frames;
  table.fps = scene.output.fps;
  table.threads = core::thread_count();
  table.cpu = cpu_model();
  table.device = o.device;
  const RunSetup setup{exe, fs::absolute(o.scene_file), frames, o.max_memory_mib, o.device, compare_view(targets)};
  FF_CHECK(write_still(o.out_dir / "target.png", targets, setup.view, true));
  for (std::size_t k = 0; k < entries.size(); ++k) {
    const auto& e = *entries[k];
    spdlog::info("compare [{}/{}] {}: {} frames ...", k + 1, entries.size(), e.name, frames);
    FF_TRY(CompareRow row, run_controller(setup, e, o.out_dir / std::string(e.name)));
    spdlog::info("compare [{}/{}] {}: {}, E {} %, {} s per frame, {} MB ({:.1f} s)", k + 1, entries.size(), e.name,
                 row.status, fixed(row.error_rate_pct, 3), fixed(row.frame_seconds, 4), fixed(row.memory_mb, 0),
                 row.wall_seconds);
    if (!std::isfinite(table.particles)) table.particles = row.particles;
    table.rows.push_back(std::move(row));
    FF_CHECK(write_tables(o.out_dir, table));
  }
  return table;
}

}  // namespace ff::pipeline
