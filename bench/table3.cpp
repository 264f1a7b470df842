// The paper's Table 3 (issue 5): every registered controller on eight scenes that mirror the paper's (Hand,
// Dragon, Dog, Vase, Building, Carbontube, Warrior, Multi-target), one `fluidform compare` child process per
// scene, then one table grouped by scene.
//   build/release/bench/bench_table3 [--quick] [--only NAME] [--controllers LIST] [--frames N] [--keep DIR]
//                                    [--meshes-only]
// The scenes are bench/scenes/*.json (full size: ~10k to ~240k particles, 300 frames). Their procedural meshes
// are not committed: this program writes them into bench/scenes/meshes/ first (--meshes-only stops there, so
// `fluidform compare bench/scenes/NAME.json` works by hand). --quick runs the same scenes from copies in the work
// folder with ~2k control particles (1.2k per target with several) and 150 frames. Output: DIR/table3.md and DIR/table3.csv, and
// each scene's compare folder DIR/NAME/ (DIR: --keep, else a fresh temporary folder, kept and printed).
#include "pipeline/compare.h"
#include "support/shapes.h"
#include "support/test_support.h"

#include <fmt/chrono.h>
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>

#include <array>
#include <chrono>
#include <cmath>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <optional>
#include <string>
#include <vector>

namespace fs = std::filesystem;
using nlohmann::json;
using namespace ff;

namespace {

constexpr std::array<const char*, 8> kScenes{"hand", "dragon", "dog", "vase", "building", "carbontube", "warrior", "multi"};
// --quick: small enough that 8 scenes × 7 controllers finish in minutes on 2 cores, large enough that the thin
// parts (fingers, wings, tubes, sword) are still a few particles across.
// Measured on an idle 2-core machine: 2500 per target (7.5k in the three-target scene) took 10 min 45 s for the
// whole quick table, the slow baselines (weighted, lcat) on the multi-target scene alone 3 min; hence 2000 per
// target, and 1200 per target where there are several.
constexpr int kQuickPerTarget = 2000;
constexpr int kQuickPerTargetMulti = 1200;
constexpr int kQuickFrames = 150;

struct Args {
  bool quick = false, meshes_only = false;
  std::string only, controllers, frames;
  fs::path keep;
};

bool parse_args(int argc, char** argv, Args& a) {
  for (int i = 1; i < argc; ++i) {
    const std::string s = argv[i];
    const bool has_value = i + 1 < argc;
    if (s == "--quick") a.quick = true;
    else if (s == "--meshes-only") a.meshes_only = true;
    else if (s == "--only" && has_value) a.only = argv[++i];
    else if (s == "--controllers" && has_value) a.controllers = argv[++i];
    else if (s == "--frames" && has_value) a.frames = argv[++i];
    else if (s == "--keep" && has_value) a.keep = argv[++i];
    else return false;
  }
  return true;
}

io::TriangleMesh rotated_z(io::TriangleMesh m, float degrees) {
  const float a = degrees * 3.14159265f / 180.0f, c = std::cos(a), s = std::sin(a);
  for (auto& v : m.vertices) v = Vec3f(c * v.x() - s * v.y(), s * v.x() + c * v.y(), v.z());
  return m;
}

io::TriangleMesh part(const Vec3f& half, const Vec3f& at, float degrees_z = 0.0f) {
  return test::translate(rotated_z(test::box(half), degrees_z), at);
}

// The paper's Hand: a wrist, a palm, four fingers of different lengths and a thumb angled out; ~1 m tall.
io::TriangleMesh hand() {
  io::TriangleMesh m = part(Vec3f(0.11f, 0.1f, 0.05f), Vec3f(0, 0.1f, 0));
  m = test::merge(m, part(Vec3f(0.2f, 0.22f, 0.06f), Vec3f(0, 0.4f, 0)));
  const std::array<float, 4> length{0.14f, 0.17f, 0.16f, 0.12f};
  for (int f = 0; f < 4; ++f) {
    const float x = -0.15f + 0.1f * float(f), h = length[static_cast<std::size_t>(f)];
    m = test::merge(m, part(Vec3f(0.034f, h, 0.034f), Vec3f(x, 0.6f + h, 0)));
  }
  return test::merge(m, part(Vec3f(0.035f, 0.13f, 0.035f), Vec3f(0.27f, 0.45f, 0), -40.0f));
}

// The paper's Dog: body, four legs, neck, head with a snout, and a raised tail; ~1.1 m long.
io::TriangleMesh dog() {
  io::TriangleMesh m = part(Vec3f(0.32f, 0.12f, 0.12f), Vec3f(0, 0.42f, 0));
  for (const float x : {-0.24f, 0.24f})
    for (const float z : {-0.075f, 0.075f}) m = test::merge(m, part(Vec3f(0.045f, 0.16f, 0.045f), Vec3f(x, 0.16f, z)));
  m = test::merge(m, part(Vec3f(0.06f, 0.1f, 0.06f), Vec3f(0.33f, 0.58f, 0), -30.0f));
  m = test::merge(m, test::translate(test::uv_sphere(0.11f, 24), Vec3f(0.42f, 0.7f, 0)));
  m = test::merge(m, part(Vec3f(0.08f, 0.045f, 0.05f), Vec3f(0.53f, 0.67f, 0)));
  return test::merge(m, part(Vec3f(0.025f, 0.14f, 0.025f), Vec3f(-0.4f, 0.6f, 0), 40.0f));
}

// The paper's Building: a tower with thin (0.07 m) wings in both directions and a spire; 1.4 m tall.
io::TriangleMesh building() {
  io::TriangleMesh m = part(Vec3f(0.15f, 0.6f, 0.15f), Vec3f(0, 0.6f, 0));
  for (const float s : {-1.0f, 1.0f}) {
    m = test::merge(m, part(Vec3f(0.32f, 0.42f, 0.035f), Vec3f(0.45f * s, 0.42f, 0)));
    m = test::merge(m, part(Vec3f(0.035f, 0.3f, 0.28f), Vec3f(0, 0.3f, 0.41f * s)));
  }
  return test::merge(m, part(Vec3f(0.03f, 0.12f, 0.03f), Vec3f(0, 1.3f, 0)));
}

// The paper's Warrior: the star figure (thin limbs) holding a thin sword with a guard at its right hand.
io::TriangleMesh warrior() {
  io::TriangleMesh m = test::star_figure();
  m = test::merge(m, part(Vec3f(0.02f, 0.32f, 0.02f), Vec3f(0.5f, 1.0f, 0)));
  return test::merge(m, part(Vec3f(0.07f, 0.015f, 0.025f), Vec3f(0.5f, 0.76f, 0)));
}

// Writes the procedural meshes the scene files name (meshes/*.obj), and the bunny of examples/ if it is missing
// (scripts/setup normally writes it).
bool write_meshes(const fs::path& source) {
  const fs::path dir = source / "bench" / "scenes" / "meshes";
  fs::create_directories(dir);
  test::write_obj(dir / "hand.obj", hand());
  test::write_obj(dir / "dog.obj", dog());
  test::write_obj(dir / "vase.obj", test::vase(1.0f, 0.35f, 0.05f));
  test::write_obj(dir / "building.obj", building());
  test::write_obj(dir / "carbontube.obj", test::tube_lattice());
  test::write_obj(dir / "warrior.obj", warrior());
  const fs::path bunny_obj = source / "examples" / "bunny.obj";
  if (fs::exists(bunny_obj)) return true;
  auto bunny = test::stanford_bunny();
  if (!bunny) {
    fmt::print(stderr, "bench_table3: {} is missing and {}\n", bunny_obj.string(), bunny.error().message);
    return false;
  }
  test::write_obj(bunny_obj, *bunny);
  return true;
}

json read_json(const fs::path& p) {
  std::ifstream in(p);
  const std::string text{std::istreambuf_iterator<char>(in), {}};
  return json::parse(text, nullptr, false, /*ignore_comments=*/true);
}

// A reduced copy of a scene in `dir`: fewer control particles and frames, mesh paths made absolute (they are
// relative to the scene file, which moves).
fs::path quick_scene(const fs::path& scene, const fs::path& dir) {
  json s = read_json(scene);
  if (s.is_discarded()) return scene;  // compare reports the broken file itself
  const std::size_t targets = s.contains("targets") ? s["targets"].size() : 1;
  s["sampling"]["auto_count"] = targets > 1 ? kQuickPerTargetMulti * static_cast<int>(targets) : kQuickPerTarget;
  s["output"]["frames"] = kQuickFrames;
  for (auto& t : s["targets"])
    if (t.contains("mesh")) t["mesh"] = fs::absolute(scene.parent_path() / t["mesh"].get<std::string>()).lexically_normal().string();
  const fs::path out = dir / scene.filename();
  std::ofstream(out) << s.dump(2) << "\n";
  return out;
}

std::string read_text(const fs::path& p) {
  std::ifstream in(p);
  return {std::istreambuf_iterator<char>(in), {}};
}

struct SceneResult {
  std::string name;
  std::optional<pipeline::CompareTable> table;
  std::string failure;  // when compare itself did not produce a table
  double wall_seconds = 0;
};

SceneResult run_scene(const Args& a, const std::string& name, const fs::path& scene_file, const fs::path& dir) {
  SceneResult r{name, std::nullopt, "", 0};
  std::vector<std::string> argv{test::binary().string(), "compare", scene_file.string(), "-o", (dir / name).string()};
  if (!a.controllers.empty()) argv.insert(argv.end(), {"--controllers", a.controllers});
  if (!a.frames.empty()) argv.insert(argv.end(), {"--frames", a.frames});
  const auto start = std::chrono::steady_clock::now();
  // The scene's own table (compare's stdout) goes to stderr with its progress: stdout keeps only the final table.
  auto exit = pipeline::run_child(argv, {}, {}, /*stdout_to_stderr=*/true);
  r.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (!exit || !exit->ok()) {
    r.failure = exit ? "compare: " + exit->describe() : exit.error().message;
    return r;
  }
  auto table = pipeline::table_from_json(read_json(dir / name / "table.json"));
  if (table) r.table = std::move(*table);
  else r.failure = "compare: no table.json";
  return r;
}

std::string combined_markdown(const std::vector<SceneResult>& results, const Args& a, double total_seconds) {
  const auto cols = pipeline::markdown_columns();
  std::string threads = "?", cpu = pipeline::cpu_model();
  for (const auto& r : results)
    if (r.table) threads = std::to_string(r.table->threads);
  std::string s = fmt::format("# Table 3 (fluidform, {} mode), {:%Y-%m-%d}: {} threads, {}\n\n", a.quick ? "quick" : "full",
                              fmt::localtime(std::time(nullptr)), threads, cpu);
  s += "| scene | particles | frames | " + fmt::format("{}", fmt::join(cols, " | ")) + " |\n|---|---:|---:|";
  for (std::size_t i = 0; i < cols.size(); ++i) s += i == 0 ? "---|" : "---:|";
  s += "\n";
  bool any_approx = false;
  for (const auto& r : results) {
    if (!r.table) {
      std::vector<std::string> cells(cols.size(), "n/a");
      cells.back() = "failure (" + r.failure + ")";
      s += fmt::format("| {} | n/a | n/a | {} |\n", r.name, fmt::join(cells, " | "));
      continue;
    }
    for (const auto& row : r.table->rows) {
      const std::string particles = std::isfinite(row.particles) ? fmt::format("{:.0f}", row.particles) : "n/a";
      s += fmt::format("| {} | {} | {} | {} |\n", r.name, particles, r.table->frames, fmt::join(pipeline::markdown_cells(row), " | "));
      any_approx = any_approx || row.approximation;
    }
  }
  if (any_approx) s += "\n[A]: an approximation of a method whose details are not public (METHOD.md §b).\n";
  s += "\nWall time per scene (all controllers, sampling and I/O included):";
  for (const auto& r : results) s += fmt::format(" {} {:.0f} s;", r.name, r.wall_seconds);
  s += fmt::format(" total {:.0f} s.\n", total_seconds);
  return s;
}

// The scenes' table.csv files, one header (they all have the same columns, the scene in the first).
std::string combined_csv(const std::vector<SceneResult>& results, const fs::path& dir) {
  std::string out;
  for (const auto& r : results) {
    if (!r.table) continue;
    const std::string csv = read_text(dir / r.name / "table.csv");
    const auto eol = csv.find('\n');
    if (eol == std::string::npos) continue;
    if (out.empty()) out = csv.substr(0, eol + 1);
    out += csv.substr(eol + 1);
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  Args a;
  if (!parse_args(argc, argv, a)) {
    fmt::print(stderr, "usage: bench_table3 [--quick] [--only NAME] [--controllers LIST] [--frames N] [--keep DIR] "
                       "[--meshes-only]\n");
    return 2;
  }
  const fs::path source = test::source_dir();
  if (!write_meshes(source)) return 1;
  if (a.meshes_only) {
    fmt::print("meshes written to {}\n", (source / "bench" / "scenes" / "meshes").string());
    return 0;
  }
  const fs::path dir = a.keep.empty() ? test::temp_dir("table3") : a.keep;
  fs::create_directories(dir / "scenes");
  const auto start = std::chrono::steady_clock::now();
  std::vector<SceneResult> results;
  for (const char* name : kScenes) {
    if (!a.only.empty() && std::string(name).find(a.only) == std::string::npos) continue;
    fs::path scene = source / "bench" / "scenes" / (std::string(name) + ".json");
    if (a.quick) scene = quick_scene(scene, dir / "scenes");
    fmt::print(stderr, "== {} ({})\n", name, scene.string());
    results.push_back(run_scene(a, name, scene, dir));
  }
  const double total = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const std::string md = combined_markdown(results, a, total);
  std::ofstream(dir / "table3.md") << md;
  std::ofstream(dir / "table3.csv") << combined_csv(results, dir);
  fmt::print("{}\n-> {}\n", md, (dir / "table3.md").string());
  for (const auto& r : results)
    if (!r.table) return 1;
  return 0;
}
