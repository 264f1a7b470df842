// fluidform command line (DESIGN.md "The CLI and output contract").
// Exit codes: 0 ok, 2 bad input or usage, 1 runtime failure. Errors are one line on stderr.
#include "pipeline/compare.h"
#include "app/progress_bar.h"
#include "pipeline/mesh_export.h"
#include "pipeline/run.h"
#include "control/registry.h"
#include "io/atomic_file.h"
#include "io/load_mesh.h"
#include "io/particle_frames.h"
#include "scene/scene.h"
#include "sampling/control_io.h"
#include "sampling/samplers.h"
#include "server/serve.h"
#include "surface/surface_params.h"

#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <filesystem>
#include <unistd.h>

namespace fs = std::filesystem;

namespace {

int fail(const ff::Error& e) {
  std::string msg = e.message;
  for (char& c : msg)
    if (c == '\n' || c == '\r') c = ' ';
  fmt::print(stderr, "fluidform: error: {}\n", msg);
  return e.is_input() ? 2 : 1;
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

int cmd_run(const fs::path& scene_file, const ff::pipeline::RunOptions& opt) {
  auto scene = ff::scene::load_scene(scene_file);
  if (!scene) return fail(scene.error());
  spdlog::info("scene {} -> {}", scene_file.string(), opt.out_dir.string());
  ff::app::ProgressBar bar(stderr);
  auto sum = ff::pipeline::run_scene(*scene, opt, bar);
  if (!sum) return fail(sum.error());
  spdlog::info("done: {} particles, {} frames, {:.2f} ms per frame (simulation only), peak memory {:.0f} MiB -> {}",
               sum->particles, sum->frames_written, 1e3 * sum->mean_frame_seconds, sum->peak_memory_mib,
               opt.out_dir.string());
  if (opt.mesh)
    spdlog::info("mesh: {} frame(s) in {:.2f} s; final.obj {} triangles, {} -> {}", sum->mesh_frames, sum->mesh_seconds,
                 sum->mesh_triangles, sum->mesh_ok ? "watertight and manifold" : "NOT watertight/manifold",
                 (opt.out_dir / "mesh" / "final.obj").string());
  if (sum->has_targets && spdlog::get_level() <= spdlog::level::info) {  // -q: no summary
    // The one-screen summary (issue 4): the paper's Table 3 columns and the numbers that keep E honest.
    fmt::print(stdout,
               "\n  controller           {}\n"
               "  controlled           {} of {} fluid particles ({} control particles, ratio {:.2f})\n"
               "  error rate           {:.3f} %  ({:.2f} spacings; mean of the last 20 % of frames)\n"
               "  inside the target    {:.2f} %\n"
               "  splash               {:.2f} %\n"
               "  E_fwd over all fluid {:.4f} m\n"
               "  time to form         {:.2f} s simulated\n"
               "  per-frame time       {:.2f} ms ({:.1f} frames per second of wall time)\n"
               "  peak memory          {:.0f} MiB\n\n",
               sum->controller, sum->controlled, sum->particles, sum->control_particles,
               sum->control_particles ? double(sum->controlled) / double(sum->control_particles) : 0.0, sum->error_rate,
               sum->error_spacings, 100.0 * sum->inside_fraction, 100.0 * sum->splash_fraction, sum->e_fwd_all,
               sum->time_to_form, 1e3 * sum->mean_frame_seconds,
               sum->mean_frame_seconds > 0 ? 1.0 / sum->mean_frame_seconds : 0.0, sum->peak_memory_mib);
  }
  return 0;
}

struct SampleOptions {
  fs::path mesh, out;
  std::string method = "blue-noise";
  std::vector<float> drop_box;  // 6 numbers per box
  ff::sampling::SamplingParams params;
};

int cmd_sample(SampleOptions o) {
  const auto m = ff::sampling::parse_method(o.method);
  if (!m) return fail(ff::param_error(fmt::format("--method {} is not one of blue-noise, voxel, surface", o.method)));
  o.params.method = *m;
  if (o.drop_box.size() % 6 != 0)
    return fail(ff::param_error("--drop-box takes 6 numbers per box: min x y z, max x y z"));
  for (std::size_t i = 0; i < o.drop_box.size(); i += 6) {
    ff::sampling::DropBox b;
    b.min = ff::Vec3f(o.drop_box[i], o.drop_box[i + 1], o.drop_box[i + 2]);
    b.max = ff::Vec3f(o.drop_box[i + 3], o.drop_box[i + 4], o.drop_box[i + 5]);
    o.params.sparse.drop_boxes.push_back(b);
  }
  if (auto st = o.params.validate(); !st.ok()) return fail(st.error());
  // Check the output before the (possibly long) sampling.
  const fs::path dir = o.out.has_parent_path() ? o.out.parent_path() : fs::path(".");
  if (auto st = ff::io::ensure_writable_dir(dir); !st.ok()) return fail(st.error());
  auto mesh = ff::io::load_mesh(o.mesh);
  if (!mesh) return fail(mesh.error());
  ff::app::ProgressBar bar(stderr);
  ff::sampling::SampleReport rep;
  auto set = ff::sampling::sample_target(*mesh, o.params, 0, &rep, bar);
  if (!set) return fail(set.error());
  for (const auto& w : rep.warnings) spdlog::warn("{}", w);
  if (auto st = ff::sampling::write_controls_ply(o.out, *set); !st.ok()) return fail(st.error());
  spdlog::info("{} control particles ({}, spacing {:g} m, volume {:g} m^3, {} dropped) in {:.2f} s -> {}", set->size(),
               ff::sampling::method_name(rep.method), rep.spacing, rep.volume, rep.dropped, rep.seconds, o.out.string());
  return 0;
}

struct MeshCliOptions {
  fs::path input, out;
  ff::pipeline::MeshOptions mesh;
  bool no_glb = false, no_pc2 = false, no_frames = false, final_only = false, no_quantize = false;
  std::string extraction = "mc";
};

int cmd_mesh(MeshCliOptions o) {
  o.mesh.glb = !o.no_glb, o.mesh.pc2 = !o.no_pc2, o.mesh.frame_objs = !o.no_frames, o.mesh.final_only = o.final_only;
  o.mesh.quantize = !o.no_quantize;
  auto extraction = ff::surface::parse_extraction(o.extraction);
  if (!extraction) return fail(ff::param_error("--extraction " + extraction.error().message));
  o.mesh.params.extraction = *extraction;
  if (auto st = o.mesh.validate(); !st.ok()) return fail(st.error());
  auto frames = ff::io::particle_frames(o.input);
  if (!frames) return fail(frames.error());
  spdlog::info("mesh: {} particle frame(s) from {} -> {}", frames->size(), o.input.string(), o.out.string());
  ff::app::ProgressBar bar(stderr);
  auto sum = ff::pipeline::export_meshes(*frames, o.out, o.mesh, bar);
  if (!sum) return fail(sum.error());
  spdlog::info("mesh: {} frame(s) meshed in {:.2f} s at spacing {:.4g} m; final.obj: {} triangles, {} vertices ({} from "
               "marching {}), {}, genus {}, {} component(s) -> {}",
               sum->frames_meshed, sum->seconds, sum->spacing, sum->final_triangles, sum->final_vertices,
               sum->mc_triangles_final,
               o.mesh.params.extraction == ff::surface::Extraction::MarchingTetrahedra ? "tetrahedra" : "cubes",
               sum->final_ok ? "watertight and manifold" : "NOT watertight/manifold",
               sum->final_genus, sum->final_components, (o.out / "mesh" / "final.obj").string());
  return sum->final_ok ? 0 : fail(ff::numerical_error("mesh: the final mesh failed its checks"));
}

struct CompareCliOptions {
  ff::pipeline::CompareOptions compare;
  std::string controllers;  // comma-separated; empty = every registered controller
  int frames = 0;
};

int cmd_compare(CompareCliOptions o) {
  // Every name is checked before anything runs or is written: a typo must not cost a long table.
  if (!o.controllers.empty()) {
    auto names = ff::pipeline::parse_controller_list(o.controllers);
    if (!names) return fail(names.error());
    o.compare.controllers = std::move(*names);
  }
  if (o.frames > 0) o.compare.frames = o.frames;
  auto table = ff::pipeline::run_compare(o.compare);
  if (!table) return fail(table.error());
  fmt::print(stdout, "{}", ff::pipeline::table_markdown(*table));
  spdlog::info("compare: {} and table.csv in {}", (o.compare.out_dir / "table.md").string(), o.compare.out_dir.string());
  return 0;
}

struct ServeCliOptions {
  ff::server::ServeOptions serve;
  std::string controller;
  bool as_fast_as_possible = false;
};

int cmd_serve(ServeCliOptions o) {
  if (!o.controller.empty()) {
    if (!ff::control::find_controller(o.controller))
      return fail(ff::param_error(fmt::format("--controller {} is not one of: {}", o.controller, ff::control::controller_names())));
    o.serve.controller = o.controller;
  }
  o.serve.realtime = !o.as_fast_as_possible;
  if (!fs::exists(o.serve.input)) return fail(ff::input_error(fmt::format("{}: no such scene file or run folder", o.serve.input.string())));
  ff::app::ProgressBar bar(stderr);
  if (auto st = ff::server::serve(o.serve, bar); !st.ok()) return fail(st.error());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  auto logger = spdlog::stderr_color_mt("fluidform");
  spdlog::set_default_logger(logger);
  spdlog::set_pattern(::isatty(2) ? "%^%l%$: %v" : "[%H:%M:%S] %l: %v");

  CLI::App app{"fluidform: editable mesh animations from controllable particles"};
  app.set_version_flag("--version", FF_VERSION);
  bool quiet = false;
  app.add_flag("-q,--quiet", quiet, "only warnings and errors");
  app.fallthrough();  // global flags such as -q also work after the subcommand

  fs::path scene_file;
  ff::pipeline::RunOptions run_opt;
  int frames = 0;
  auto* run = app.add_subcommand("run", "simulate a scene file into an output folder");
  run->add_option("scene", scene_file, "scene file (JSON)")->required();
  run->add_option("-o,--out", run_opt.out_dir, "output folder")->capture_default_str();
  run->add_option("--frames", frames, "output frames to simulate (overrides output.frames)")->check(CLI::Range(1, 10'000'000));
  run->add_flag("--resume", run_opt.resume, "continue a killed run from OUT/checkpoint/");
  bool no_mesh = false;
  run->add_flag("--no-mesh", no_mesh, "do not reconstruct the last frame into OUT/mesh/final.obj");
  run->add_option("--mesh-every", run_opt.mesh_every,
                  "also mesh every k-th frame: OUT/mesh/frame_NNNNN.obj, OUT/animation.glb, OUT/particles.pc2")
      ->check(CLI::Range(1, 1'000'000));
  std::string controller_name;
  run->add_option("--controller", controller_name,
                  "shape controller: " + ff::control::controller_names() + " (overrides the scene's controller.name)");

  SampleOptions sample_opt;
  auto* sample = app.add_subcommand("sample", "sample a mesh into control particles (PLY with density, weight, phi)");
  sample->add_option("mesh", sample_opt.mesh, "mesh file (any format Assimp reads)")->required();
  sample->add_option("-o,--out", sample_opt.out, "output PLY file")->required();
  sample->add_option("--spacing", sample_opt.params.spacing, "sample spacing d in metres (default: about --count samples)");
  sample->add_option("--count", sample_opt.params.auto_count, "samples aimed at when --spacing is not given")
      ->capture_default_str();
  sample->add_option("--method", sample_opt.method, "blue-noise, voxel or surface")->capture_default_str();
  sample->add_option("--seed", sample_opt.params.seed, "random seed")->capture_default_str();
  sample->add_option("--relax-steps", sample_opt.params.relax_steps, "blue-noise relaxation steps")->capture_default_str();
  sample->add_option("--max-samples", sample_opt.params.max_samples, "refuse to make more samples")->capture_default_str();
  sample->add_option("--drop-fraction", sample_opt.params.sparse.drop_fraction,
                     "sparse sampling: remove this fraction of the samples at random");
  sample->add_option("--drop-box", sample_opt.drop_box,
                     "sparse sampling: remove the samples in the box x0 y0 z0 x1 y1 z1 (repeatable)")
      ->expected(6)->allow_extra_args(false);

  MeshCliOptions mesh_opt;
  auto* mesh = app.add_subcommand("mesh", "reconstruct particle frames into meshes, a GLB animation and a Blender point cache");
  mesh->add_option("input", mesh_opt.input, "a particle PLY, a folder of frame_NNNNN.ply, or a run's output folder")->required();
  mesh->add_option("-o,--out", mesh_opt.out, "output folder (mesh/, animation.glb, particles.pc2)")->required();
  mesh->add_option("--every", mesh_opt.mesh.every, "mesh every k-th frame (and the last)")->capture_default_str();
  mesh->add_flag("--final-only", mesh_opt.final_only, "mesh only the last frame (mesh/final.obj)");
  mesh->add_option("--spacing", mesh_opt.mesh.spacing, "particle spacing d in metres (default: from the frames' header, or estimated)");
  mesh->add_option("--triangles", mesh_opt.mesh.params.max_triangles, "triangle budget per mesh (0: none)")->capture_default_str();
  mesh->add_option("--cell", mesh_opt.mesh.params.cell_size, "grid cell size in spacings")->capture_default_str();
  mesh->add_option("--smoothing", mesh_opt.mesh.params.smoothing_passes, "smoothing passes (paper eq. 20-21)")->capture_default_str();
  mesh->add_option("--extraction", mesh_opt.extraction,
                   "iso-surface extraction: mc (marching cubes) or rmt (regularised marching tetrahedra)")
      ->capture_default_str();
  mesh->add_option("--fps", mesh_opt.mesh.fps, "frames per second of the animation")->capture_default_str();
  mesh->add_flag("--no-glb", mesh_opt.no_glb, "do not write animation.glb");
  mesh->add_flag("--no-pc2", mesh_opt.no_pc2, "do not write particles.pc2 / particles_frame0.ply");
  mesh->add_flag("--no-frames", mesh_opt.no_frames, "do not write mesh/frame_NNNNN.obj");
  mesh->add_flag("--no-quantize", mesh_opt.no_quantize, "store float positions and normals in the GLB");

  CompareCliOptions cmp_opt;
  auto* compare = app.add_subcommand(
      "compare", "run controllers on a scene, one fresh process each, and tabulate the paper's Table 3 columns");
  compare->add_option("scene", cmp_opt.compare.scene_file, "scene file (JSON)")->required();
  compare->add_option("--controllers", cmp_opt.controllers,
                      "comma-separated controllers to run (default: all, listed below)");
  compare->add_option("-o,--out", cmp_opt.compare.out_dir,
                      "output folder: table.md, table.csv, table.json and one run folder per controller")
      ->capture_default_str();
  compare->add_option("--frames", cmp_opt.frames,
                      fmt::format("output frames per controller (default: the scene's output.frames, else {})",
                                  ff::pipeline::kDefaultCompareFrames))
      ->check(CLI::Range(1, 10'000'000));
  compare->footer(ff::pipeline::controllers_help());

  ServeCliOptions serve_opt;
  auto* serve = app.add_subcommand(
      "serve", "live viewer: run a scene (or play back a run's folder) and watch, steer and edit it in a browser or WebXR headset");
  serve->add_option("input", serve_opt.serve.input, "scene file (JSON), or the output folder of a finished run")->required();
  serve->add_option("--port", serve_opt.serve.server.port, "TCP port (0: any free port, printed)")
      ->capture_default_str()->check(CLI::Range(0, 65535));
  serve->add_option("--bind", serve_opt.serve.server.bind,
                    "address to listen on (loopback by default: whoever reaches the page can steer the simulation)")
      ->capture_default_str();
  serve->add_option("--max-clients", serve_opt.serve.server.max_clients, "viewers at once")->capture_default_str();
  serve->add_option("--controller", serve_opt.controller, "shape controller: " + ff::control::controller_names());
  serve->add_option("--mesh", serve_opt.serve.meshes, "another mesh for the viewer's mesh list (repeatable)");
  serve->add_option("--web", serve_opt.serve.web_dir, "the viewer's folder (default: web/ of the source tree)");
  serve->add_option("--cache", serve_opt.serve.cache_dir, "control-particle cache folder")->capture_default_str();
  serve->add_option("--exit-after", serve_opt.serve.exit_after, "stop after this many seconds (default: at Ctrl-C)");
  serve->add_flag("--as-fast-as-possible", serve_opt.as_fast_as_possible,
                  "simulate as fast as the machine can (default: at most real time)");
  serve->add_option("--max-fps", serve_opt.serve.max_fps,
                    "at most this many simulated frames per second of wall time (default 0: no cap)");

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::string msg = e.what();
    return fail(ff::param_error(msg + " (see fluidform --help)"));
  }
  if (quiet) spdlog::set_level(spdlog::level::warn);
  run_opt.mesh = !no_mesh;
  if (frames > 0) run_opt.frames = frames;
  if (!controller_name.empty()) {
    if (!ff::control::find_controller(controller_name))
      return fail(ff::param_error(fmt::format("--controller {} is not one of: {}", controller_name, ff::control::controller_names())));
    run_opt.controller = controller_name;
  }

  if (*run) return cmd_run(scene_file, run_opt);
  if (*sample) return cmd_sample(std::move(sample_opt));
  if (*mesh) return cmd_mesh(std::move(mesh_opt));
  if (*compare) return cmd_compare(std::move(cmp_opt));
  if (*serve) return cmd_serve(std::move(serve_opt));
  // No sub-command: the bundled default scene into ./fluidform-out.
  return cmd_run(default_scene(), ff::pipeline::RunOptions{});
}
