#include "pipeline/run.h"

#include "pipeline/mesh_export.h"

#include "pipeline/auto_scene.h"
#include "pipeline/scene_setup.h"

#include "core/memory.h"
#include "core/parallel.h"
#include "core/timer.h"
#include "io/atomic_file.h"
#include "io/load_mesh.h"
#include "io/particle_frames.h"
#include "io/write_ply.h"
#include "sim/checkpoint.h"
#include "sim/emitter.h"
#include "sim/pbf_solver.h"
#include "control/registry.h"
#include "metrics/report.h"
#include "metrics/shape_metrics.h"
#include "metrics/summary.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include <fstream>
#include <iterator>

namespace ff::pipeline {
namespace fs = std::filesystem;
using metrics::FrameRow;
using metrics::TargetRow;
using nlohmann::json;

namespace {

/// Mean wall-clock of the simulated frames (frame 0 is the initial state, not simulated).
double mean_step_seconds(const std::vector<FrameRow>& rows) {
  double total = 0.0;
  int n = 0;
  for (const auto& r : rows)
    if (r.frame > 0) total += r.step_seconds, ++n;
  return n ? total / n : 0.0;
}

Status write_frame(const fs::path& out, int frame, const sim::ParticleSet& p, bool velocity, float spacing,
                   std::vector<Vec3f>& x, std::vector<Vec3f>& v, std::vector<std::uint8_t>& t) {
  sim::sorted_by_id(p, x, v, t);
  io::ParticleFrameView view;
  // The spacing lets `fluidform mesh` size its grid without guessing.
  const std::string comment = fmt::format("fluidform particles\nspacing {:.9g}", spacing);
  view.comment = comment;
  view.positions = x;
  if (velocity) view.velocities = v;
  view.targets = t;
  return io::write_particles_ply(io::frame_path(out, frame), view);
}

Result<std::vector<std::uint8_t>> read_bytes(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  if (!in) return input_error(fmt::format("{}: cannot read", p.string()));
  return std::vector<std::uint8_t>(std::istreambuf_iterator<char>(in), {});
}

}  // namespace

namespace {

/// Per-frame shape metrics of every target (app/scene_setup.h), and their N_c-weighted aggregate into `row`.
void measure_frame(const std::vector<TargetShapes>& shapes, const std::vector<control::TargetMotion>& motion,
                   double time, const sim::ParticleSet& p, float r, int frame, std::vector<std::uint8_t>& controlled,
                   FrameRow& row, std::vector<TargetRow>& target_rows) {
  if (shapes.empty()) return;
  const ShapeMeasure m = measure_targets(shapes, motion, time, p, r, controlled);
  for (std::size_t t = 0; t < m.per_target.size(); ++t) target_rows.push_back({frame, static_cast<int>(t), m.per_target[t]});
  row.controlled = m.controlled;
  row.error_rate = m.error_rate, row.e_fwd = m.e_fwd, row.e_bwd = m.e_bwd, row.e_fwd_all = m.e_fwd_all;
  row.inside = m.inside, row.splash = m.splash;
}

/// The adaptive run length: the shape has formed and held when E(t) over the last `window` frames stays within
/// a band of 0.05 percentage points plus 5 % of its mean, after at least `min_frames`.
bool formed_and_held(const std::vector<FrameRow>& rows, int window, int min_frames) {
  if (static_cast<int>(rows.size()) < std::max(window, min_frames) + 1) return false;
  double lo = INFINITY, hi = -INFINITY, sum = 0;
  for (std::size_t k = rows.size() - static_cast<std::size_t>(window); k < rows.size(); ++k) {
    const double e = rows[k].error_rate;
    if (!std::isfinite(e)) return false;
    lo = std::min(lo, e), hi = std::max(hi, e), sum += e;
  }
  return hi - lo <= 0.05 + 0.05 * (sum / window);
}

}  // namespace

Result<RunSummary> run_scene(const scene::Scene& scene_in, const RunOptions& opt, core::Progress& progress) {
  const fs::path out = opt.out_dir;
  const fs::path ckpt_dir = out / "checkpoint", ckpt_file = ckpt_dir / "state.ffck";
  scene::Scene scene = scene_in;
  if (opt.controller) scene.controller.name = *opt.controller;
  FF_CHECK(scene.controller.validate());

  // Targets are loaded and checked first so that a bad mesh fails fast; a scene that names only its
  // targets is completed from them (spacing, fluid, domain).
  FF_TRY(auto geometry, load_targets(scene));
  FF_CHECK(complete_scene(scene, geometry));
  const bool run_until_formed = !opt.frames && scene.auto_frames && !geometry.empty();
  const int frames = opt.frames.value_or(run_until_formed ? opt.max_auto_frames : scene.output.frames);
  if (!(frames >= 1 && frames <= 10'000'000))
    return param_error(fmt::format("--frames = {} is outside [1, 10000000]", frames));
  if (opt.frames) scene.output.frames = frames, scene.auto_frames = false;  // the report's scene is the run's

  // The fluid is made (and its size checked) before the output folder is touched.
  sim::ParticleSet initial;
  if (!opt.resume || !fs::exists(ckpt_file)) {
    FF_CHECK(sim::fill_sources(scene.fluid, scene.domain, scene.solver.particle_radius, initial));
    assign_targets(initial, geometry);
  }

  // Inputs are all checked before the output folder is touched.
  FF_CHECK(io::ensure_writable_dir(out));
  FF_CHECK(io::ensure_writable_dir(out / "particles"));
  if (scene.output.checkpoint_every > 0) FF_CHECK(io::ensure_writable_dir(ckpt_dir));

  // Control particles of every target (METHOD §a.1), cached in OUT/cache by mesh content and parameters.
  FF_TRY(PreparedTargets prepared, prepare_targets(scene, geometry, out / "cache", out, progress));
  json targets_json = std::move(prepared.info);
  std::vector<control::ControlTarget> controls = std::move(prepared.controls);
  std::vector<TargetShapes> shapes = std::move(prepared.shapes);
  std::vector<control::TargetMotion> motions = std::move(prepared.motions);

  sim::ParticleSet particles;
  std::vector<FrameRow> rows;
  std::vector<TargetRow> target_rows;
  int next_frame = 1;
  double time = 0.0;
  std::vector<Vec3f> xs, vs;
  std::vector<std::uint8_t> ts, flags;

  bool resumed = false;
  if (opt.resume && fs::exists(ckpt_file)) {
    if (const auto n = io::remove_stale_temp_files(out))
      spdlog::info("removed {} partial file(s) left by the interrupted run", n);
    FF_TRY(auto bytes, read_bytes(ckpt_file));
    auto ck = sim::decode_checkpoint(bytes);
    if (!ck) return input_error(fmt::format("{}: {}", ckpt_file.string(), ck.error().message));
    if (ck->scene_hash != scene.hash)
      return input_error(fmt::format("{}: the checkpoint was made from a different scene; run without --resume to start over",
                                     ckpt_file.string()));
    particles = std::move(ck->particles);
    next_frame = static_cast<int>(ck->next_frame);
    time = ck->time;
    const json extra = json::parse(ck->extra, nullptr, false);
    if (!extra.is_discarded() && extra.contains("rows")) rows = metrics::rows_from_json(extra["rows"]);
    if (!extra.is_discarded() && extra.contains("target_rows")) target_rows = metrics::target_rows_from_json(extra["target_rows"]);
    resumed = true;
    spdlog::info("resuming from frame {} (t = {:.4f} s, {} particles)", next_frame, time, particles.size());
  } else if (opt.resume) {
    spdlog::warn("--resume: no checkpoint in {}, starting from the beginning", ckpt_dir.string());
  }
  if (!resumed) {
    particles = std::move(initial);
    FF_CHECK(write_frame(out, 0, particles, scene.output.velocity, scene.solver.spacing(), xs, vs, ts));
    FrameRow row{0, 0.0, particles.size(), 0.0, 0, 0, 0.0, 0.0, core::peak_rss_mib()};
    measure_frame(shapes, motions, 0.0, particles, scene.solver.particle_radius, 0, flags, row, target_rows);
    rows.push_back(row);
  }
  if (particles.size() == 0) return input_error("the scene creates no fluid particles");

  sim::PbfSolver solver(scene.solver, scene.domain);
  control::ControlContext ctx{scene.solver.particle_radius, solver.particle_mass(), scene.solver.rest_density,
                              scene.solver.gravity, scene.domain, scene.solver.support()};
  // A scene without targets has nothing to control: plain PBF whatever the controller setting.
  control::ControllerSpec spec = scene.controller;
  if (controls.empty()) spec.name = "none";
  const std::size_t control_count = prepared.control_count;
  FF_TRY(auto controller, control::make_controller(spec, std::move(controls), ctx));
  spdlog::info("{} particles, d = {} m, H_p = {} m, rho0 = {:.1f} kg/m^3 (lattice-calibrated), controller {}, {} threads",
               particles.size(), scene.solver.spacing(), scene.solver.support(), solver.rest_density(),
               controller->name(), core::thread_count());

  const double frame_dt = 1.0 / scene.output.fps;
  sim::StageTimes stages;  // summed over the frames this process simulated (not those before a --resume)
  auto totals = [&]() {
    double peak = 0.0;
    for (const auto& r : rows) peak = std::max(peak, r.peak_memory_mib);
    json t = {{"particles", particles.size()},
              {"control_particles", control_count},
              // Particles a controller added during the run (lcat's temporaries); 0 for every other controller.
              {"added_particles", rows.empty() ? 0 : particles.size() - rows.front().particles},
              {"controller", std::string(controller->name())},
              {"frames", rows.empty() ? 0 : rows.back().frame},
              {"simulated_seconds", rows.empty() ? 0.0 : rows.back().time},
              {"mean_step_time_s", mean_step_seconds(rows)},
              {"peak_memory_mb", peak},
              {"threads", core::thread_count()},
              {"rest_density", solver.rest_density()},
              {"particle_mass", solver.particle_mass()},
              {"stage_seconds", {{"neighbors", stages.neighbors}, {"forces", stages.forces}, {"control", stages.control},
                                 {"solve", stages.solve}, {"update", stages.update}}}};
    if (!shapes.empty() && !rows.empty()) {
      std::vector<double> e, times;
      for (const auto& r : rows) e.push_back(r.error_rate), times.push_back(r.time);
      const auto sum = metrics::summarize(e, times);
      const auto tail = metrics::tail_window(rows.size(), 0.2);
      auto tail_mean = [&](auto field) {
        std::vector<double> v;
        for (const auto& r : rows) v.push_back(field(r));
        return metrics::window_mean(v, tail);
      };
      const auto& last = rows.back();
      t["error_rate_pct"] = metrics::json_number(sum.steady);
      t["error_rate_final_pct"] = metrics::json_number(sum.final_value);
      t["time_to_form_s"] = metrics::json_number(sum.time_to_form);
      t["time_to_form_stable_s"] = metrics::json_number(sum.time_to_form_stable);
      t["e_fwd_m"] = metrics::json_number(tail_mean([](const FrameRow& r) { return r.e_fwd; }));
      t["e_bwd_m"] = metrics::json_number(tail_mean([](const FrameRow& r) { return r.e_bwd; }));
      t["e_fwd_all_m"] = metrics::json_number(tail_mean([](const FrameRow& r) { return r.e_fwd_all; }));
      t["inside_fraction"] = metrics::json_number(tail_mean([](const FrameRow& r) { return r.inside; }));
      t["splash_fraction"] = metrics::json_number(tail_mean([](const FrameRow& r) { return r.splash; }));
      t["controlled_final"] = last.controlled;
      t["controlled_per_control"] = control_count ? double(last.controlled) / double(control_count) : 0.0;
      json per = json::array();
      double es_w = 0.0, es_n = 0.0;
      for (std::size_t k = 0; k < shapes.size(); ++k) {
        std::vector<double> ek, tk;
        const TargetRow* lastk = nullptr;
        for (const auto& r : target_rows)
          if (r.target == static_cast<int>(k)) ek.push_back(r.m.error_rate), tk.push_back(r.frame * frame_dt), lastk = &r;
        const auto sk = metrics::summarize(ek, tk);
        per.push_back({{"target", k},
                       {"error_rate_pct", metrics::json_number(sk.steady)},
                       {"time_to_form_s", metrics::json_number(sk.time_to_form)},
                       {"fluid", lastk ? lastk->m.fluid : 0},
                       {"controlled", lastk ? lastk->m.controlled : 0},
                       {"inside_fraction", lastk ? metrics::json_number(lastk->m.inside_fraction) : json(nullptr)},
                       {"splash_fraction", lastk ? metrics::json_number(lastk->m.splash_fraction) : json(nullptr)},
                       {"error_spacings", metrics::json_number(sk.steady * shapes[k].shape.back().diagonal() / (100.0 * scene.solver.spacing()))}});
        es_w += double(shapes[k].shape.back().sample_count()) * sk.steady * shapes[k].shape.back().diagonal() /
                (100.0 * scene.solver.spacing());
        es_n += double(shapes[k].shape.back().sample_count());
      }
      t["per_target"] = per;
      t["error_spacings"] = metrics::json_number(es_w / es_n);
    }
    return t;
  };
  auto write_report = [&](std::string_view status, std::string_view error) -> Status {
    json rep;
    rep["fluidform_version"] = FF_VERSION;
    rep["status"] = status;
    if (!error.empty()) rep["error"] = error;
    rep["scene_file"] = scene.file.string();
    rep["scene"] = scene::scene_to_json(scene);  // every key the run used: run it again to reproduce the run
    rep["targets"] = targets_json;
    rep["totals"] = totals();
    FF_CHECK(io::write_file_atomic(out / "metrics.csv", metrics::metrics_csv(rows)));
    if (!shapes.empty()) FF_CHECK(io::write_file_atomic(out / "metrics_targets.csv", metrics::target_metrics_csv(target_rows)));
    return io::write_file_atomic(out / "report.json", rep.dump(2) + "\n");
  };

  progress.begin(run_until_formed ? "forming" : "simulating", static_cast<std::size_t>(frames));
  progress.tick(static_cast<std::size_t>(next_frame - 1));
  bool warned_cap = false;
  int last_frame = next_frame - 1;
  const int window = static_cast<int>(std::lround(scene.output.fps));  // 1 s of frames
  for (int f = next_frame; f <= frames; ++f) {
    core::Stopwatch watch;
    auto stats = solver.advance(particles, time, frame_dt, *controller);
    const double seconds = watch.seconds();
    if (!stats) {
      progress.end();
      const std::string msg = fmt::format("frame {}: {}", f, stats.error().message);
      (void)write_report("failed", msg);
      return Error{stats.error().kind, msg};
    }
    if (stats->substeps_capped && !warned_cap) {
      spdlog::warn("frame {}: the CFL condition wanted more than solver.max_substeps = {} sub-steps", f,
                   scene.solver.max_substeps);
      warned_cap = true;
    }
    time = f * frame_dt;
    FF_CHECK(write_frame(out, f, particles, scene.output.velocity, scene.solver.spacing(), xs, vs, ts));
    FrameRow row{f, time, particles.size(), seconds, stats->substeps, stats->times.iterations, stats->density_error_mean,
                 stats->density_error_max, core::peak_rss_mib()};
    row.control_seconds = stats->times.control;
    stages.neighbors += stats->times.neighbors, stages.forces += stats->times.forces, stages.solve += stats->times.solve;
    stages.control += stats->times.control, stages.update += stats->times.update;
    measure_frame(shapes, motions, time, particles, scene.solver.particle_radius, f, flags, row, target_rows);
    rows.push_back(row);
    last_frame = f;
    const bool done = run_until_formed && formed_and_held(rows, window, 2 * window);
    if (scene.output.checkpoint_every > 0 && (f % scene.output.checkpoint_every == 0 || f == frames || done)) {
      sim::Checkpoint ck{f + 1, time, scene.hash,
                         json{{"rows", metrics::rows_to_json(rows)}, {"target_rows", metrics::target_rows_to_json(target_rows)}}.dump(),
                         particles};
      FF_CHECK(io::write_file_atomic(ckpt_file, sim::encode_checkpoint(ck)));
      FF_CHECK(write_report("running", ""));
    }
    if (!progress.tick(static_cast<std::size_t>(f))) return Error{Error::Kind::Cancelled, "cancelled"};
    if (done) break;
  }
  progress.end();
  FF_CHECK(write_report("ok", ""));
  if (run_until_formed && last_frame == frames && !formed_and_held(rows, window, 2 * window))
    spdlog::warn("the shape had not settled after {} frames (the cap); pass --frames to run longer", frames);

  RunSummary sum;
  sum.particles = particles.size();
  sum.frames_written = last_frame + 1;
  sum.mean_frame_seconds = mean_step_seconds(rows);
  sum.peak_memory_mib = core::peak_rss_mib();
  sum.controller = std::string(controller->name());
  if (!shapes.empty()) {
    const json t = totals();
    sum.has_targets = true;
    sum.control_particles = control_count;
    auto get = [&](const char* k) { return t.contains(k) && t[k].is_number() ? t[k].get<double>() : NAN; };
    sum.error_rate = get("error_rate_pct");
    sum.inside_fraction = get("inside_fraction");
    sum.splash_fraction = get("splash_fraction");
    sum.time_to_form = get("time_to_form_s");
    sum.controlled = rows.back().controlled;
    sum.e_fwd_all = get("e_fwd_all_m");
    sum.error_spacings = get("error_spacings");
  }
  // The editable mesh of the last frame (and with --mesh-every the mesh animation and the point cache), from the
  // particle frames just written; a failure here leaves the simulation's outputs as they are.
  if (opt.mesh) {
    std::vector<fs::path> files;
    for (int k = 0; k <= last_frame; ++k) files.push_back(io::frame_path(out, k));
    MeshOptions mo;
    mo.spacing = scene.solver.spacing();
    mo.fps = scene.output.fps;
    if (opt.mesh_every > 0) mo.every = opt.mesh_every;
    else mo.final_only = true;
    auto ms = export_meshes(files, out, mo, progress);
    if (!ms) return Error{ms.error().kind, "meshing: " + ms.error().message};
    sum.mesh_triangles = ms->final_triangles;
    sum.mesh_ok = ms->final_ok;
    sum.mesh_frames = ms->frames_meshed;
    sum.mesh_seconds = ms->seconds;
  }
  return sum;
}

}  // namespace ff::pipeline
