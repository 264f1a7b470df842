// `fluidform run SCENE.json`: simulate a scene into an output folder, mesh its last frame, print the summary.
#include "app/cli.h"
#include "app/progress_bar.h"
#include "pipeline/run.h"
#include "scene/scene.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <cmath>
#include <memory>
#include <string>

namespace ff::app {
namespace fs = std::filesystem;

namespace {

struct RunCli {
  fs::path scene_file;
  pipeline::RunOptions run;
  int frames = 0;
  bool no_mesh = false, no_animation = false;
  std::string controller;
  double max_memory = 0.0;
};

// "Formed" as report.json's time_to_form_s counts it (metrics::FormedThresholds), with the thresholds it used.
std::string time_to_form_text(double t, const metrics::FormedThresholds& th) {
  const std::string when = fmt::format("inside ≥ {:g} %, splash ≤ {:g} %", 100 * th.min_inside, 100 * th.max_splash);
  if (!std::isfinite(t)) return fmt::format("not formed ({} not reached by the end)", when);
  return fmt::format("{:.2f} s simulated ({} from then on)", t, when);
}

// The one-screen summary: the paper's Table 3 columns and the numbers that keep E honest.
void print_summary(const pipeline::RunSummary& sum) {
  fmt::print(stdout,
             "\n  controller           {}\n"
             "  controlled           {} of {} fluid particles ({} control particles, ratio {:.2f})\n"
             "  error rate           {:.3f} %  ({:.2f} spacings; mean of the last 20 % of frames)\n"
             "  inside the target    {:.2f} %\n"
             "  splash               {:.2f} %\n"
             "  E_fwd over all fluid {:.4f} m\n"
             "  time to form         {}\n"
             "  per-frame time       {:.2f} ms ({:.1f} frames per second of wall time)\n"
             "  peak memory          {:.0f} MiB\n\n",
             sum.controller, sum.controlled, sum.particles, sum.control_particles,
             sum.control_particles ? double(sum.controlled) / double(sum.control_particles) : 0.0, sum.error_rate,
             sum.error_spacings, 100.0 * sum.inside_fraction, 100.0 * sum.splash_fraction, sum.e_fwd_all,
             time_to_form_text(sum.time_to_form, sum.formed), 1e3 * sum.mean_frame_seconds,
             sum.mean_frame_seconds > 0 ? 1.0 / sum.mean_frame_seconds : 0.0, sum.peak_memory_mib);
}

int run_scene_file(const fs::path& scene_file, const pipeline::RunOptions& opt) {
  auto scene = scene::load_scene(scene_file);
  if (!scene) return fail(scene.error());
  spdlog::info("scene {} -> {}", scene_file.string(), opt.out_dir.string());
  ProgressBar bar(stderr);
  auto sum = pipeline::run_scene(*scene, opt, bar);
  if (!sum) return fail(sum.error());
  spdlog::info("done: {} particles, {} frames, {:.2f} ms per frame (simulation only), peak memory {:.0f} MiB -> {}",
               sum->particles, sum->frames_written, 1e3 * sum->mean_frame_seconds, sum->peak_memory_mib,
               opt.out_dir.string());
  if (opt.mesh)
    spdlog::info("mesh: {} frame(s) in {:.2f} s; final.obj {} triangles, {} -> {}{}", sum->mesh_frames, sum->mesh_seconds,
                 sum->mesh_triangles, sum->mesh_ok ? "watertight and manifold" : "NOT watertight/manifold",
                 (opt.out_dir / "mesh" / "final.obj").string(),
                 sum->mesh_frames > 1 ? ", " + (opt.out_dir / "animation.glb").string() : std::string());
  if (sum->rigged) spdlog::info("rig: the formed mesh with its target's skeleton and clips -> {}", (opt.out_dir / "rigged.glb").string());
  if (sum->has_targets && spdlog::get_level() <= spdlog::level::info) print_summary(*sum);  // -q: no summary
  return 0;
}

// The bundled default scene: next to the binary's source tree (build/<preset>/src/app → examples/),
// or where the build was configured from.
fs::path default_scene() {
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    for (fs::path p = exe.parent_path(); !p.empty() && p != p.root_path(); p = p.parent_path()) {
      const fs::path cand = p / "examples" / "default_scene.json";
      if (fs::exists(cand)) return cand;
    }
  }
  return fs::path(FF_SOURCE_DIR) / "examples" / "default_scene.json";
}

}  // namespace

Command add_run(CLI::App& app) {
  auto o = std::make_shared<RunCli>();
  auto* run = app.add_subcommand("run", "simulate a scene file into an output folder");
  run->add_option("scene", o->scene_file, "scene file (JSON), or a mesh file (OBJ, FBX, glTF, PLY, STL, ...): the smallest scene around it")->required();
  run->add_option("-o,--out", o->run.out_dir, "output folder")->capture_default_str();
  run->add_option("--frames", o->frames, "output frames to simulate (overrides output.frames)")->check(CLI::Range(1, 10'000'000));
  run->add_flag("--resume", o->run.resume, "continue a killed run from OUT/checkpoint/");
  run->add_flag("--no-mesh", o->no_mesh, "do not reconstruct the last frame into OUT/mesh/final.obj (nor the animation)");
  run->add_flag("--no-animation", o->no_animation,
                "mesh only the last frame: no OUT/animation.glb and no OUT/particles.pc2 point cache");
  run->add_option("--mesh-every", o->run.mesh_every,
                  "also mesh every k-th frame: OUT/mesh/frame_NNNNN.obj, OUT/animation.glb, OUT/particles.pc2")
      ->check(CLI::Range(1, 1'000'000));
  run->add_flag("--vdb", o->run.vdb, "also write each meshed frame's level set: OUT/vdb/frame_NNNNN.vdb (OpenVDB)");
  run->add_option("--max-memory", o->max_memory, "MiB the run may need, estimated before it starts (overrides limits.max_memory_mb)")
      ->check(CLI::Range(1.0, 1e9));
  add_controller_option(run, o->controller, " (overrides the scene's controller.name)");
  run->add_option("--device", o->run.device,
                  "cpu, gpu (Vulkan; lavapipe where there is no GPU) or auto (a GPU when there is one and the scene is one "
                  "the GPU path does, else the CPU); docs/gpu.md")
      ->check(CLI::IsMember({"cpu", "gpu", "auto"}))
      ->capture_default_str();
  return {run, [o] {
            o->run.mesh = !o->no_mesh;
            o->run.animation = !o->no_animation;
            if (o->max_memory > 0.0) o->run.max_memory_mib = o->max_memory;
            if (o->frames > 0) o->run.frames = o->frames;
            if (!o->controller.empty()) o->run.controller = o->controller;
            return run_scene_file(o->scene_file, o->run);
          }};
}

int run_default_scene() { return run_scene_file(default_scene(), pipeline::RunOptions{}); }

}  // namespace ff::app
