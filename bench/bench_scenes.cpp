// The controller's scene benchmark (issue 4): each scene run by `fluidform run` in its own process (so peak
// memory is its own), with the defaults only, then one table of the paper's Table 3 columns and the numbers
// that keep E honest (METHOD §d). Scenes: the bunny, a thin-limbed star figure, a hollow vase, a torus, a
// lattice of thin tubes, the bunny with 30 % of its samples removed in a box, and three targets at once.
//   build/release/bench/bench_scenes [--quick] [--ablations] [--speed] [--hard] [--particles N] [--only NAME] [--frames N]
//                                    [--keep DIR] [--patch JSON]
// --quick: ~3k control particles per scene instead of ~10k; --particles N: ~N. --ablations: the bunny and the star with each
// component of `adaptive` switched off or set to its paper reading. --speed: the speed scenes, the bunny
// at ~10k and ~100k particles and the three-target scene. Runs stop once formed (cap 600 frames) unless --frames
// is given. Frame times are medians over the run's frames (metrics.csv): over all of them, and over the frames
// after the shape formed (steady state, what a viewer sees once the forming is done). --patch: a JSON merge patch
// (RFC 7386) applied to every scene, to compare a setting against the defaults with one build, e.g.
// --patch '{"solver":{"cfl":0.8}}'. The family includes a moving target: the bunny carried 0.4 m sideways and
// turned 45° while it forms. --hard: the hard targets (issue 44) with the defaults, so the count comes from their
// walls: an open-top box and a pipe whose walls are 1.5 spacings at 10k particles, a gear-like disc, a file of
// overlapping parts, the three targets, and the demo character walking 8× as fast (its fastest vertex's speed in
// the name). Every row gives the formed mesh's genus and parts and the share of the target's solid it holds.
#include "io/load_mesh.h"
#include "io/skin.h"
#include "pipeline/auto_scene.h"
#include "sampling/mesh_field.h"
#include "sampling/samplers.h"
#include "scene/scene.h"
#include "support/shapes.h"
#include "support/test_support.h"
#include "surface/mesh_check.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;
using nlohmann::json;
using namespace ff;

namespace {

struct Scene {
  std::string name;
  json scene;
};

std::string run(const std::string& cmd) {
  std::string out;
  FILE* f = ::popen(cmd.c_str(), "r");
  if (!f) return out;
  char buf[4096];
  while (std::fgets(buf, sizeof buf, f)) out += buf;
  ::pclose(f);
  return out;
}

double median(std::vector<double> v) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  const std::size_t h = v.size() / 2;
  return v.size() % 2 ? v[h] : 0.5 * (v[h - 1] + v[h]);
}

// What metrics.csv says besides the report's totals: the median step time (ms) over all simulated frames and over
// those after `formed_s`, and from `formed_s` on the least inside and the most splash (%; NaN when never formed).
struct FrameFigures {
  double all_ms = NAN, formed_ms = NAN, least_inside = NAN, most_splash = NAN;
};
FrameFigures frame_figures(const fs::path& csv, double formed_s) {
  std::ifstream in(csv);
  std::string line;
  std::getline(in, line);
  std::vector<std::string> head;
  for (std::stringstream ss(line); std::getline(ss, line, ',');) head.push_back(line);
  const auto col = [&](const char* name) { return std::find(head.begin(), head.end(), name) - head.begin(); };
  const auto c_time = col("time_s"), c_step = col("step_time_s"), c_sub = col("substeps");
  const auto c_inside = col("inside_fraction"), c_splash = col("splash_fraction");
  std::vector<double> all, formed;
  FrameFigures r;
  while (std::getline(in, line)) {
    std::vector<std::string> f;
    for (std::stringstream ss(line); std::getline(ss, line, ',');) f.push_back(line);
    if (f.size() < head.size() || std::stod(f[static_cast<std::size_t>(c_sub)]) == 0) continue;  // frame 0: not stepped
    const double ms = 1e3 * std::stod(f[static_cast<std::size_t>(c_step)]);
    all.push_back(ms);
    if (!std::isfinite(formed_s) || std::stod(f[static_cast<std::size_t>(c_time)]) < formed_s - 1e-6) continue;  // time_s: 6 decimals
    formed.push_back(ms);
    const double inside = 100 * std::stod(f[static_cast<std::size_t>(c_inside)]);
    const double splash = 100 * std::stod(f[static_cast<std::size_t>(c_splash)]);
    r.least_inside = std::isnan(r.least_inside) ? inside : std::min(r.least_inside, inside);
    r.most_splash = std::isnan(r.most_splash) ? splash : std::max(r.most_splash, splash);
  }
  r.all_ms = median(all), r.formed_ms = median(formed);
  return r;
}

// What the formed mesh of a run says about holes: its genus and components (surface/mesh_check.h), and the share
// of the target's solid it holds (lattice points at half the particle spacing inside the target that are inside
// the formed mesh: a hole through a thin wall shows as a lost share, a wall formed too thin as a smaller one). The
// share is NaN for a target that moves or is skinned (its final pose is not its bind pose) or more than one target.
struct MeshFigures {
  int genus = -1;
  std::size_t components = 0;
  double held = NAN;
};
MeshFigures mesh_figures(const fs::path& scene_file, const fs::path& formed_obj, const json& scene_json) {
  MeshFigures r;
  auto formed = io::load_mesh(formed_obj);
  if (!formed) return r;
  const surface::MeshCheck check = surface::check_mesh(*formed);
  r.genus = check.genus, r.components = check.components;
  const json& targets = scene_json["targets"];
  if (targets.size() != 1 || targets[0].contains("keyframes") || targets[0].contains("animation")) return r;
  auto s = scene::load_scene(scene_file);
  if (!s) return r;
  auto g = pipeline::load_target_meshes(*s);
  auto field = sampling::MeshField::build(*formed);
  if (!g || g->empty() || !(*g)[0].field || !field) return r;
  const float h = 0.5f * static_cast<float>(std::cbrt((*g)[0].field->volume() / 1e5));  // ~800k points
  std::size_t in = 0, all = 0;
  for (const Vec3f& x : sampling::voxel_samples(*(*g)[0].field, h)) ++all, in += field->inside(x) ? 1 : 0;
  r.held = all ? 100.0 * double(in) / double(all) : NAN;
  return r;
}

// The fastest a vertex of the scene's first target moves over its first `span` seconds (m/s): its skinned pose,
// differenced over 1/240 s. 0 for a target without a clip.
double fastest_vertex(const fs::path& scene_file, double span) {
  auto s = scene::load_scene(scene_file);
  if (!s) return NAN;
  auto g = pipeline::load_target_meshes(*s);
  if (!g || g->empty() || !(*g)[0].skin) return 0.0;
  const auto& t = (*g)[0];
  const pose::TargetSkin& sk = *t.skin;
  constexpr double dt = 1.0 / 240.0;
  std::vector<io::Mat4f> k0, k1;
  double fastest = 0.0;
  for (double time = 0.0; time < span; time += dt) {
    sk.world_joint_matrices(time, k0);
    sk.world_joint_matrices(time + dt, k1);
    for (std::size_t v = 0; v < t.mesh.vertices.size(); ++v) {
      const Vec3f a = io::skin_point(k0, sk.skin.joints[v], sk.skin.weights[v], t.mesh.vertices[v]);
      const Vec3f b = io::skin_point(k1, sk.skin.joints[v], sk.skin.weights[v], t.mesh.vertices[v]);
      fastest = std::max(fastest, double((b - a).norm()) / dt);
    }
  }
  return fastest;
}

}  // namespace

int main(int argc, char** argv) {
  bool quick = false, ablations = false, speed = false, hard = false;
  std::string only, frames;
  int particles = 0;
  json patch = json::object();
  fs::path keep;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--quick") quick = true;
    else if (a == "--ablations") ablations = true;
    else if (a == "--speed") speed = true;
    else if (a == "--hard") hard = true;
    else if (a == "--only" && i + 1 < argc) only = argv[++i];
    else if (a == "--frames" && i + 1 < argc) frames = argv[++i];
    else if (a == "--particles" && i + 1 < argc) particles = std::atoi(argv[++i]);
    else if (a == "--keep" && i + 1 < argc) keep = argv[++i];
    else if (a == "--patch" && i + 1 < argc) {
      patch = json::parse(argv[++i], nullptr, false);
      if (patch.is_discarded() || !patch.is_object()) {
        fmt::print(stderr, "bench_scenes: --patch wants a JSON object\n");
        return 2;
      }
    }
    else {
      fmt::print(stderr, "usage: bench_scenes [--quick] [--ablations] [--speed] [--hard] [--particles N] [--only NAME] [--frames N] "
                          "[--keep DIR] [--patch JSON]\n");
      return 2;
    }
  }
  const fs::path dir = keep.empty() ? test::temp_dir("scenes") : keep;
  fs::create_directories(dir);
  auto bunny = test::stanford_bunny();
  if (!bunny) {
    fmt::print(stderr, "{}\n", bunny.error().message);
    return 1;
  }
  test::write_obj(dir / "bunny.obj", *bunny);
  test::write_obj(dir / "star.obj", test::star_figure());
  test::write_obj(dir / "vase.obj", test::vase(1.0f, 0.35f, 0.06f));
  test::write_obj(dir / "torus.obj", test::torus(0.4f, 0.12f, 64, 24));
  test::write_obj(dir / "lattice.obj", test::tube_lattice());
  // The hard family's walls are ~1.5 spacings at 10k particles (the count their volume gives), as the issue asks.
  test::write_obj(dir / "thin-box.obj", test::open_box(Vec3f(0.5f, 0.35f, 0.4f), 0.037f));
  test::write_obj(dir / "pipe.obj", test::pipe(0.3f, 0.025f, 1.0f));
  test::write_obj(dir / "gear.obj", test::gear(24, 0.4f, 0.5f, 0.03f));
  test::write_obj(dir / "parts.obj", test::overlapping_parts());
  if (particles != 0 && !(particles >= 100 && particles <= 100'000'000)) {
    fmt::print(stderr, "bench_scenes: --particles wants a count in [100, 1e8]\n");
    return 2;
  }
  const int count = particles ? particles : quick ? 3000 : 10000;
  auto target = [](const char* mesh, json extra = json::object()) {
    json t = {{"mesh", mesh}};
    for (auto& [k, v] : extra.items()) t[k] = v;
    return t;
  };
  auto scene = [&](json targets, json extra = json::object()) {
    json s = {{"targets", targets}, {"sampling", {{"auto_count", count}}}};
    for (auto& [k, v] : extra.items()) s[k] = v;
    return s;
  };
  const json bunny_t = target("bunny.obj", {{"scale", 0.1}});
  std::vector<Scene> scenes;
  const json three = {target("bunny.obj", {{"scale", 0.06}, {"translate", {-0.9, 0, 0}}}),
                      target("torus.obj", {{"scale", 0.7}, {"translate", {0, 0.2, 0}}}),
                      target("vase.obj", {{"scale", 0.7}, {"translate", {0.9, 0, 0}}})};
  // The hard family runs with the defaults (the count from the targets' walls) unless --particles names a count.
  auto hard_scene = [&](json targets) {
    json sc = {{"targets", targets}};
    if (particles) sc["sampling"] = {{"auto_count", particles}};
    return sc;
  };
  const fs::path character = test::source_dir() / "examples" / "generated" / "character.glb";
  if (hard) {
    scenes.push_back({"thin-box", hard_scene({target("thin-box.obj")})});
    scenes.push_back({"pipe", hard_scene({target("pipe.obj")})});
    scenes.push_back({"gear", hard_scene({target("gear.obj")})});
    scenes.push_back({"overlapping-parts", hard_scene({target("parts.obj")})});
    scenes.push_back({"three-targets", hard_scene(three)});
    // The demo character's walk played 8× as fast: its hands and feet move at the speed the table prints.
    if (fs::exists(character))
      scenes.push_back({"character-fast", hard_scene({target(character.c_str(), {{"animation",
          {{"clip", "walk"}, {"speed", 8.0}, {"loop", true}}}})})});
    else
      fmt::print(stderr, "bench_scenes: {} is missing (scripts/setup writes it): no character-fast\n", character.string());
  } else if (speed) {
    scenes.push_back({"bunny", scene({bunny_t})});
    scenes.push_back({"bunny-100k", scene({bunny_t}, {{"sampling", {{"auto_count", quick ? 30000 : 100000}}}})});
    scenes.push_back({"three-targets", scene(three)});
  } else if (!ablations) {
    scenes.push_back({"bunny", scene({bunny_t})});
    scenes.push_back({"star", scene({target("star.obj")})});
    scenes.push_back({"vase", scene({target("vase.obj")})});
    scenes.push_back({"torus", scene({target("torus.obj")})});
    scenes.push_back({"lattice", scene({target("lattice.obj")})});
    // Sparse: 30 % of the bunny's samples removed in a box (its head and ears side, x ≤ −0.17 m; paper Fig. 3).
    scenes.push_back({"bunny-sparse", scene({bunny_t}, {{"sampling", {{"auto_count", count},
        {"sparse", {{"drop_boxes", json::array({{{"min", {-0.5, 0.0, -0.4}}, {"max", {-0.17, 1.0, 0.4}}}})}}}}}})});
    scenes.push_back({"three-targets", scene(three)});
    scenes.push_back({"bunny-moving", scene({target("bunny.obj", {{"scale", 0.1}, {"keyframes", json::array({
        {{"time", 0.5}, {"translate", {0, 0, 0}}}, {{"time", 2.5}, {"translate", {0.4, 0, 0}}, {"rotate", {0, 45, 0}}}})}})})});
  } else {
    const std::vector<std::pair<std::string, json>> variants = {
        {"default", json::object()},
        {"weights off", {{"weights", false}}},
        {"boundary correction off", {{"boundary_correction", false}}},
        {"bond radius: paper", {{"bond_radius", "paper"}}},
        {"bond breaking off", {{"bond_breaking", false}}},
        {"gather off", {{"gather", false}}},
        {"kinematic control", {{"kinematic", true}}}};
    for (const auto& [shape, t] : {std::pair{std::string("bunny"), bunny_t}, std::pair{std::string("star"), target("star.obj")}})
      for (const auto& [vname, v] : variants)
        scenes.push_back({shape + ", " + vname, scene({t}, {{"controller", {{"adaptive", v}}}})});
  }
  fmt::print("| scene | particles | controls | controlled/N_c | E (%) | E (d) | inside (%) | splash (%) | E_fwd all (m) "
             "| time to form (s) | least inside, formed (%) | most splash, formed (%) | frame, all (ms) | frame, formed (ms) "
             "| fps, formed | memory (MiB) | mesh genus (parts) | target held by mesh (%) |\n"
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (std::size_t k = 0; k < scenes.size(); ++k) {
    const auto& s = scenes[k];
    if (!only.empty() && s.name.find(only) == std::string::npos) continue;
    const fs::path file = dir / fmt::format("scene_{}.json", k), out = dir / fmt::format("out_{}", k);
    json patched = s.scene;
    patched.merge_patch(patch);
    std::ofstream(file) << patched.dump(2);
    const std::string cmd = fmt::format("'{}' -q run '{}' -o '{}' {} 2>&1", test::binary().string(), file.string(),
                                        out.string(), frames.empty() ? "" : "--frames " + frames);
    const std::string log = run(cmd);
    std::ifstream in(out / "report.json");
    json rep = json::parse(in, nullptr, false);
    if (rep.is_discarded() || !rep.contains("totals") || rep["status"] != "ok") {
      fmt::print("| {} | failure | | | | | | | | | | | | | | | | |\n", s.name);
      fmt::print(stderr, "{}: {}\n", s.name, log);
      continue;
    }
    const json& t = rep["totals"];
    auto num = [&](const char* key) { return t.contains(key) && t[key].is_number() ? t[key].get<double>() : NAN; };
    // time_to_form_s is null when the shape never stayed formed (≥ 99 % inside, ≤ 0.5 % splash for 1 s).
    const FrameFigures ff = frame_figures(out / "metrics.csv", num("time_to_form_s"));
    const MeshFigures mf = mesh_figures(file, out / "mesh" / "final.obj", patched);
    std::string name = s.name;
    if (s.name == "character-fast") name += fmt::format(" ({:.0f} m/s)", fastest_vertex(file, 2.0));
    fmt::print("| {} | {} | {} | {:.2f} | {:.3f} | {:.2f} | {:.2f} | {:.2f} | {:.4f} | {} | {:.2f} | {:.2f} | {:.1f} | {:.1f} "
               "| {:.1f} | {:.0f} | {} ({}) | {:.1f} |\n",
               name, t["particles"].get<long>(), t["control_particles"].get<long>(), num("controlled_per_control"),
               num("error_rate_pct"), num("error_spacings"), 100 * num("inside_fraction"), 100 * num("splash_fraction"),
               num("e_fwd_all_m"), std::isfinite(num("time_to_form_s")) ? fmt::format("{:.2f}", num("time_to_form_s")) : "not formed",
               ff.least_inside, ff.most_splash, ff.all_ms, ff.formed_ms, 1e3 / ff.formed_ms, num("peak_memory_mb"), mf.genus,
               mf.components, mf.held);
    std::fflush(stdout);
  }
  if (keep.empty()) fs::remove_all(dir);
  return 0;
}
