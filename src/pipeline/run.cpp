#include "pipeline/run.h"
#include "pipeline/report_page.h"

#include "pipeline/stepper.h"
#include "pose/skin_eval.h"

#include "io/write_vdb.h"

#include "pipeline/mesh_export.h"

#include "pipeline/auto_scene.h"
#include "pipeline/run_budget.h"
#include "pose/skin_transfer.h"
#include "io/write_rigged_glb.h"
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

#include <algorithm>
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
void measure_frame(const std::vector<TargetShapes>& shapes, const std::vector<pose::TargetMotion>& motion,
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

/// The stop rule of a run without --frames: E has settled over the last `window` frames (formed_and_held) and the
/// shape is formed (metrics::FormedThresholds: inside and splash) and has stayed so for the last second.
bool settled_and_formed(const std::vector<FrameRow>& rows, int window) {
  if (!formed_and_held(rows, window, 2 * window)) return false;
  std::vector<double> inside, splash, times;
  for (const auto& r : rows) inside.push_back(r.inside), splash.push_back(r.splash), times.push_back(r.time);
  return metrics::formed_held(inside, splash, times);
}

}  // namespace

namespace {

fs::path checkpoint_file(const fs::path& out) { return out / "checkpoint" / "state.ffck"; }
fs::path previous_checkpoint_file(const fs::path& out) { return out / "checkpoint" / "state.prev.ffck"; }
bool has_checkpoint(const fs::path& out) {
  return fs::exists(checkpoint_file(out)) || fs::exists(previous_checkpoint_file(out));
}

/// What a run carries from frame to frame; a checkpoint restores it.
struct RunState {
  sim::ParticleSet particles;
  std::vector<FrameRow> rows;
  std::vector<TargetRow> target_rows;
  int next_frame = 1;
  double time = 0.0;
  double first_frame_seconds = 0.0;  // the calibration: wall time of the first frame this process simulated
  sim::StageTimes stages;  // summed over the frames this process simulated (not those before a --resume)
};

/// What report.json says about a run besides its rows: fixed once the controller is made.
struct RunFacts {
  const scene::Scene& scene;
  nlohmann::json targets;                    // report.json "targets"
  const std::vector<TargetShapes>& shapes;   // empty: no targets, no shape metrics
  std::size_t control_count = 0;
  std::string controller;
  std::string device;                        // report.json "device": "cpu", or the GPU's name and driver
  double rest_density = 0, particle_mass = 0;
  RunEstimate estimate;                      // report.json "estimate"
};

/// The checkpoint at `file`, decoded.
Result<sim::Checkpoint> load_checkpoint(const fs::path& file) {
  FF_TRY(auto bytes, read_bytes(file));
  auto ck = sim::decode_checkpoint(bytes);
  if (!ck) return input_error(fmt::format("{}: {}", file.string(), ck.error().message));
  return std::move(*ck);
}

/// Restores `st` from OUT/checkpoint; false when there is none to resume from. A newest checkpoint that cannot be
/// read (truncated, corrupt, or gone because the run was killed between keeping the old one and writing the new
/// one) falls back to the one before, with a warning.
Result<bool> resume_from_checkpoint(const fs::path& out, std::uint64_t scene_hash, RunState& st) {
  const fs::path ckpt_file = checkpoint_file(out), prev_file = previous_checkpoint_file(out);
  if (!has_checkpoint(out)) {
    spdlog::warn("--resume: no checkpoint in {}, starting from the beginning", ckpt_file.parent_path().string());
    return false;
  }
  fs::path used = ckpt_file;
  auto ck = fs::exists(ckpt_file) ? load_checkpoint(ckpt_file)
                                  : Result<sim::Checkpoint>(input_error(fmt::format("{}: missing", ckpt_file.string())));
  if (!ck && fs::exists(prev_file)) {
    spdlog::warn("--resume: {}; resuming from the checkpoint before it", ck.error().message);
    ck = load_checkpoint(used = prev_file);
    // The unreadable newest one goes, so the next checkpoint does not rename it over the good one.
    std::error_code ec;
    if (ck) fs::remove(ckpt_file, ec);
  }
  if (!ck) return ck.error();
  if (ck->scene_hash != scene_hash)
    return input_error(fmt::format("{}: the checkpoint was made from a different scene; run without --resume to start over",
                                   used.string()));
  st.particles = std::move(ck->particles);
  st.next_frame = static_cast<int>(ck->next_frame);
  st.time = ck->time;
  const json extra = json::parse(ck->extra, nullptr, false);
  if (!extra.is_discarded() && extra.contains("rows")) st.rows = metrics::rows_from_json(extra["rows"]);
  if (!extra.is_discarded() && extra.contains("target_rows")) st.target_rows = metrics::target_rows_from_json(extra["target_rows"]);
  spdlog::info("resuming from frame {} (t = {:.4f} s, {} particles)", st.next_frame, st.time, st.particles.size());
  return true;
}

/// Writes a checkpoint, keeping the one before it as state.prev.ffck (a rename, so at every instant one of the two
/// is a whole checkpoint).
Status write_checkpoint(const fs::path& out, const sim::Checkpoint& ck) {
  const fs::path file = checkpoint_file(out);
  std::error_code ec;
  if (fs::exists(file)) {
    fs::rename(file, previous_checkpoint_file(out), ec);
    if (ec) return io_error(fmt::format("{}: cannot keep the previous checkpoint: {}", file.string(), ec.message()));
  }
  return io::write_file_atomic(file, sim::encode_checkpoint(ck));
}

/// The shape totals of report.json (METHOD §d): steady error rate, time to form, tail means, and per target.
void shape_totals(const RunFacts& facts, const RunState& st, json& t) {
  const auto& rows = st.rows;
  const double frame_dt = 1.0 / facts.scene.output.fps, d = facts.scene.solver.spacing();
  std::vector<double> e, times, inside, splash;
  for (const auto& r : rows)
    e.push_back(r.error_rate), times.push_back(r.time), inside.push_back(r.inside), splash.push_back(r.splash);
  const auto sum = metrics::summarize(e, times);
  const metrics::FormedThresholds formed;
  const auto tail = metrics::tail_window(rows.size(), 0.2);
  auto tail_mean = [&](auto field) {
    std::vector<double> v;
    for (const auto& r : rows) v.push_back(field(r));
    return metrics::window_mean(v, tail);
  };
  const auto& last = rows.back();
  t["error_rate_pct"] = metrics::json_number(sum.steady);
  t["error_rate_final_pct"] = metrics::json_number(sum.final_value);
  // Formed: from when inside and splash stay within the thresholds (null: never); settled: from when E stays within
  // 10 % of its steady value.
  t["time_to_form_s"] = metrics::json_number(metrics::formed_since(inside, splash, times, formed));
  t["formed_when"] = {{"min_inside_fraction", formed.min_inside}, {"max_splash_fraction", formed.max_splash},
                      {"hold_s", formed.hold_s}};
  t["time_to_settle_s"] = metrics::json_number(sum.time_to_form);
  t["time_to_form_stable_s"] = metrics::json_number(sum.time_to_form_stable);
  t["e_fwd_m"] = metrics::json_number(tail_mean([](const FrameRow& r) { return r.e_fwd; }));
  t["e_bwd_m"] = metrics::json_number(tail_mean([](const FrameRow& r) { return r.e_bwd; }));
  t["e_fwd_all_m"] = metrics::json_number(tail_mean([](const FrameRow& r) { return r.e_fwd_all; }));
  t["inside_fraction"] = metrics::json_number(tail_mean([](const FrameRow& r) { return r.inside; }));
  t["splash_fraction"] = metrics::json_number(tail_mean([](const FrameRow& r) { return r.splash; }));
  t["controlled_final"] = last.controlled;
  t["controlled_per_control"] = facts.control_count ? double(last.controlled) / double(facts.control_count) : 0.0;
  json per = json::array();
  double es_w = 0.0, es_n = 0.0;
  for (std::size_t k = 0; k < facts.shapes.size(); ++k) {
    std::vector<double> ek, tk, ik, sk_splash;
    const TargetRow* lastk = nullptr;
    for (const auto& r : st.target_rows)
      if (r.target == static_cast<int>(k)) {
        ek.push_back(r.m.error_rate), tk.push_back(r.frame * frame_dt), lastk = &r;
        ik.push_back(r.m.inside_fraction), sk_splash.push_back(r.m.splash_fraction);
      }
    const auto sk = metrics::summarize(ek, tk);
    const auto& shape = facts.shapes[k].shape.back();
    per.push_back({{"target", k},
                   {"error_rate_pct", metrics::json_number(sk.steady)},
                   {"time_to_form_s", metrics::json_number(metrics::formed_since(ik, sk_splash, tk, formed))},
                   {"fluid", lastk ? lastk->m.fluid : 0},
                   {"controlled", lastk ? lastk->m.controlled : 0},
                   {"inside_fraction", lastk ? metrics::json_number(lastk->m.inside_fraction) : json(nullptr)},
                   {"splash_fraction", lastk ? metrics::json_number(lastk->m.splash_fraction) : json(nullptr)},
                   {"error_spacings", metrics::json_number(sk.steady * shape.diagonal() / (100.0 * d))}});
    es_w += double(shape.sample_count()) * sk.steady * shape.diagonal() / (100.0 * d);
    es_n += double(shape.sample_count());
  }
  t["per_target"] = per;
  t["error_spacings"] = metrics::json_number(es_w / es_n);
}

/// report.json's "totals".
json run_totals(const RunFacts& facts, const RunState& st) {
  const auto& rows = st.rows;
  double peak = 0.0;
  for (const auto& r : rows) peak = std::max(peak, r.peak_memory_mib);
  const sim::StageTimes& stages = st.stages;
  json t = {{"particles", st.particles.size()},
            {"control_particles", facts.control_count},
            // Particles a controller added during the run (lcat's temporaries); 0 for every other controller.
            {"added_particles", rows.empty() ? 0 : st.particles.size() - rows.front().particles},
            {"controller", facts.controller},
            {"frames", rows.empty() ? 0 : rows.back().frame},
            {"simulated_seconds", rows.empty() ? 0.0 : rows.back().time},
            {"mean_step_time_s", mean_step_seconds(rows)},
            {"peak_memory_mb", peak},
            {"threads", core::thread_count()},
            {"rest_density", facts.rest_density},
            {"particle_mass", facts.particle_mass},
            {"stage_seconds", {{"neighbors", stages.neighbors}, {"forces", stages.forces}, {"control", stages.control},
                               {"solve", stages.solve}, {"update", stages.update}}}};
  if (!facts.shapes.empty() && !rows.empty()) shape_totals(facts, st, t);
  return t;
}

/// report.json, metrics.csv and metrics_targets.csv, each written atomically.
Status write_report(const fs::path& out, const RunFacts& facts, const RunState& st, std::string_view status,
                    std::string_view error) {
  json rep;
  rep["fluidform_version"] = FF_VERSION;
  rep["status"] = status;
  if (!error.empty()) rep["error"] = error;
  rep["scene_file"] = facts.scene.file.string();
  rep["device"] = facts.device;
  rep["scene"] = scene::scene_to_json(facts.scene);  // every key the run used: run it again to reproduce the run
  rep["targets"] = facts.targets;
  rep["totals"] = run_totals(facts, st);
  rep["estimate"] = facts.estimate.to_json();
  if (const scene::AutoSizing& z = facts.scene.sizing; z.count > 0.0) {  // how the automatic count was chosen
    rep["sizing"] = {{"count_for_volume", z.count_for_volume}, {"count", std::round(z.count)},
                     {"count_for_walls", z.count_for_walls > 0.0 ? json(std::round(z.count_for_walls)) : json(nullptr)},
                     {"wall_spacings_aimed", kWallSpacings},
                     {"limited_by", z.limited_by.empty() ? json(nullptr) : json(z.limited_by)},
                     {"thinnest_wall_m", z.target >= 0 ? json(z.wall) : json(nullptr)},
                     {"thinnest_wall_target", z.target >= 0 ? json(z.target) : json(nullptr)}};
  }
  if (st.first_frame_seconds > 0.0) rep["estimate"]["seconds_per_frame"] = st.first_frame_seconds;
  FF_CHECK(io::write_file_atomic(out / "metrics.csv", metrics::metrics_csv(st.rows)));
  if (!facts.shapes.empty())
    FF_CHECK(io::write_file_atomic(out / "metrics_targets.csv", metrics::target_metrics_csv(st.target_rows)));
  return io::write_file_atomic(out / "report.json", rep.dump(2) + "\n");
}

/// The fixed inputs of the frame loop.
struct FrameLoop {
  const fs::path& out;
  const RunFacts& facts;
  const std::vector<pose::TargetMotion>& motions;
  int frames = 0;
  bool run_until_formed = false;
};

/// OUT/report.html with the meshes this run made (an earlier run's final.obj or animation.glb in the same folder is
/// kept, as everything already written is, but never shown as this run's).
Status write_page(const fs::path& out, const PageSources& made) {
  FF_TRY(const ReportPage page, write_report_page(out, made));
  spdlog::info("{}", page.describe(out));
  return {};
}

/// Simulates frames st.next_frame … loop.frames (or until the shape has formed and held), writing each particle
/// frame, its metrics row and the checkpoints; returns the last frame simulated.
// Why a frame wanted more than max_substeps: surface tension's capillary sub-step alone, at this spacing (a scene
// modelled a few centimetres small is as slow as real water that small: measured on the Collada duck at scale 0.01,
// 64 sub-steps a frame with the capillary condition, 12–37 without), or the particles' speed (the CFL condition).
std::string substep_cap_message(const sim::SolverParams& solver, double frame_dt) {
  const double capillary = solver.capillary_dt();
  const double wanted = std::ceil(frame_dt / capillary - 1e-9);
  if (std::isfinite(capillary) && wanted > double(solver.max_substeps))
    return fmt::format("surface tension at this spacing (d = {:.3g} mm) wants sub-steps of at most {:.3g} ms, {:.0f} a "
                       "frame, more than solver.max_substeps = {}: the scene is as slow as real water this small; scale "
                       "it up (targets[].scale and the domain) or set solver.capillary_cfl = 0 to run it faster",
                       1e3 * solver.spacing(), 1e3 * capillary, wanted, solver.max_substeps);
  return fmt::format("the CFL condition wanted more than solver.max_substeps = {} sub-steps", solver.max_substeps);
}

Result<int> simulate_frames(const FrameLoop& loop, RunState& st, FrameStepper& stepper, core::Progress& progress) {
  const scene::Scene& scene = loop.facts.scene;
  const double frame_dt = 1.0 / scene.output.fps;
  std::vector<Vec3f> xs, vs;
  std::vector<std::uint8_t> ts, flags;
  bool warned_cap = false;
  int last_frame = st.next_frame - 1;
  const int window = static_cast<int>(std::lround(scene.output.fps));  // 1 s of frames
  for (int f = st.next_frame; f <= loop.frames; ++f) {
    core::Stopwatch watch;
    auto stats = stepper.advance(st.particles, st.time, frame_dt);
    const double seconds = watch.seconds();
    if (!stats) {
      progress.end();
      const std::string msg = fmt::format("frame {}: {}", f, stats.error().message);
      (void)write_report(loop.out, loop.facts, st, "failed", msg);
      (void)write_page(loop.out, PageSources{false, false});  // a failed run's page says so, with its frames so far
      return Error{stats.error().kind, msg};
    }
    if (stats->substeps_capped && !warned_cap) {
      spdlog::warn("frame {}: {}", f, substep_cap_message(scene.solver, frame_dt));
      warned_cap = true;
    }
    if (st.first_frame_seconds == 0.0) {
      st.first_frame_seconds = seconds;
      // From a short calibration (this frame): a run that will take long says so at once.
      const double left = seconds * double(loop.frames - f);
      if (left > 600.0)
        spdlog::warn("frame {} took {:.2f} s: {} {:.0f} min for the {} frames left ({} particles)", f, seconds,
                     loop.run_until_formed ? "up to" : "about", left / 60.0, loop.frames - f, st.particles.size());
    }
    st.time = f * frame_dt;
    FF_CHECK(write_frame(loop.out, f, st.particles, scene.output.velocity, scene.solver.spacing(), xs, vs, ts));
    FrameRow row{f, st.time, st.particles.size(), seconds, stats->substeps, stats->times.iterations, stats->density_error_mean,
                 stats->density_error_max, core::peak_rss_mib()};
    row.control_seconds = stats->times.control;
    sim::StageTimes& stages = st.stages;
    stages.neighbors += stats->times.neighbors, stages.forces += stats->times.forces, stages.solve += stats->times.solve;
    stages.control += stats->times.control, stages.update += stats->times.update;
    measure_frame(loop.facts.shapes, loop.motions, st.time, st.particles, scene.solver.particle_radius, f, flags, row,
                  st.target_rows);
    st.rows.push_back(row);
    last_frame = f;
    const bool done = loop.run_until_formed && settled_and_formed(st.rows, window);
    if (scene.output.checkpoint_every > 0 && (f % scene.output.checkpoint_every == 0 || f == loop.frames || done)) {
      sim::Checkpoint ck{f + 1, st.time, scene.hash,
                         json{{"rows", metrics::rows_to_json(st.rows)}, {"target_rows", metrics::target_rows_to_json(st.target_rows)}}.dump(),
                         st.particles};
      FF_CHECK(write_checkpoint(loop.out, ck));
      FF_CHECK(write_report(loop.out, loop.facts, st, "running", ""));
    }
    if (!progress.tick(static_cast<std::size_t>(f))) return Error{Error::Kind::Cancelled, "cancelled"};
    if (done) break;
  }
  progress.end();
  if (loop.run_until_formed && last_frame == loop.frames && !settled_and_formed(st.rows, window))
    spdlog::warn("the shape had not formed and settled after {} frames (the cap); pass --frames to run longer", loop.frames);
  return last_frame;
}

/// What the CLI prints of a finished run.
RunSummary run_summary(const RunFacts& facts, const RunState& st, int last_frame) {
  RunSummary sum;
  sum.particles = st.particles.size();
  sum.frames_written = last_frame + 1;
  sum.mean_frame_seconds = mean_step_seconds(st.rows);
  sum.peak_memory_mib = core::peak_rss_mib();
  sum.controller = facts.controller;
  sum.device = facts.device;
  if (!facts.shapes.empty()) {
    const json t = run_totals(facts, st);
    sum.has_targets = true;
    sum.control_particles = facts.control_count;
    auto get = [&](const char* k) { return t.contains(k) && t[k].is_number() ? t[k].get<double>() : NAN; };
    sum.error_rate = get("error_rate_pct");
    sum.inside_fraction = get("inside_fraction");
    sum.splash_fraction = get("splash_fraction");
    sum.time_to_form = get("time_to_form_s");
    sum.controlled = st.rows.back().controlled;
    sum.e_fwd_all = get("e_fwd_all_m");
    sum.error_spacings = get("error_spacings");
  }
  return sum;
}

/// The editable mesh of the last frame, the mesh animation and the point cache (every animation_every()-th frame,
/// or every --mesh-every-th with its OBJs), from the particle frames just written; a failure here leaves the
/// simulation's outputs as they are.
Status mesh_run(const fs::path& out, const scene::Scene& scene, int last_frame, const RunOptions& opt,
                const LiquidLooks& looks, RunSummary& sum, core::Progress& progress) {
  std::vector<fs::path> files;
  for (int k = 0; k <= last_frame; ++k) files.push_back(io::frame_path(out, k));
  MeshOptions mo;
  mo.spacing = scene.solver.spacing();
  mo.fps = scene.output.fps;
  mo.vdb = opt.vdb;
  mo.max_memory_mib = memory_limit_mib(scene, opt.max_memory_mib);
  for (const auto& t : scene.targets) mo.target_tints.push_back(t.tint);
  mo.looks = &looks;
  if (opt.mesh_every > 0) {
    mo.every = opt.mesh_every;
  } else if (opt.animation) {
    mo.every = animation_every(last_frame + 1);
    mo.frame_objs = false;
  } else {
    mo.final_only = true;
  }
  auto ms = export_meshes(files, out, mo, progress);
  if (!ms) return Error{ms.error().kind, "meshing: " + ms.error().message};
  sum.mesh_triangles = ms->final_triangles;
  sum.mesh_ok = ms->final_ok;
  sum.mesh_frames = ms->frames_meshed;
  sum.mesh_uvs = ms->look.uvs_win();
  sum.mesh_seconds = ms->seconds;
  return {};
}

/// OUT/rigged.glb of a run whose one target is skinned: final.obj with the skin transferred from the target posed at
/// the last frame (pose/skin_transfer.h), moved to the bind pose, with the target's skeleton and clips, so that
/// it plays with no rigging step. The keyframed pose of that time, if any, is taken off first.
Status rig_final_mesh(const fs::path& out, const scene::Scene& scene, const TargetGeometry& target,
                      const pose::TargetMotion& motion, double time, const LiquidLooks& looks, RunSummary& sum) {
  auto formed = io::load_mesh(out / "mesh" / "final.obj");
  if (!formed) return Error{formed.error().kind, "rigging: " + formed.error().message};
  // The look of the final mesh, as final.obj has it (load_mesh reads positions only; one target: no labels).
  std::vector<Vec3f> colours;
  if (looks.coloured()) colours = liquid_colours(looks, *formed, {}, time);
  std::vector<std::array<io::Vec2f, 3>> uvs;  // and its UVs, when the meshes were written with them
  if (sum.mesh_uvs) uvs = liquid_uvs(looks, *formed, time);
  const Eigen::Affine3f rest = motion.at(time).rest_from_world();
  for (Vec3f& v : formed->vertices) v = rest * v;
  const pose::TargetSkin& skin = *target.skin;
  FF_TRY(pose::SkinnedSurface rigged,
         pose::transfer_skin(*formed, target.mesh, skin.skin, scene.targets[0].transform, skin.clip, skin.clip_time(time)));
  // A clip the fluid played back and forth (pose::ClipWrap) is also written baked that way, so that looping it in
  // three.js, Blender or Unity plays what the liquid did.
  io::Skin clips = skin.skin;
  if (skin.pingpong) {
    io::AnimationClip played = skin.skin.clips[static_cast<std::size_t>(skin.clip)];
    if (played.name.empty()) played.name = fmt::format("clip_{}", skin.clip);  // as write_rigged_glb names it
    clips.clips.push_back(pose::pingpong_clip(played));
  }
  rigged.bind_mesh.colours = std::move(colours);  // same vertices, same order
  if (!uvs.empty() && rigged.bind_mesh.triangles.size() == uvs.size())
    rigged.bind_mesh.corner_uv = std::move(uvs), rigged.bind_mesh.texture = looks.targets[0].texture;
  FF_CHECK(io::write_rigged_glb(out / "rigged.glb", rigged.bind_mesh, rigged.joints, rigged.weights, clips,
                                scene.targets[0].transform, scene.targets[0].tint));
  spdlog::info("rigged.glb: the final mesh in bind pose with {} joints and {} clip(s) ({} vertices by the fallback, "
               "round trip within {:.2g} m)", clips.joint_nodes.size(), clips.clips.size(), rigged.unreached,
               rigged.max_bind_error_m);
  sum.rigged = true;
  return {};
}

/// The meshes (mesh_run) in the liquid's look (targets[].appearance: read only for the meshes; a texture that cannot
/// be used only warns), and rigged.glb for one skinned target.
Status mesh_and_rig(const fs::path& out, const scene::Scene& scene, const std::vector<TargetGeometry>& geometry,
                    const std::vector<pose::TargetMotion>& motions, int last_frame, double time, const RunOptions& opt,
                    RunSummary& sum, core::Progress& progress) {
  const LiquidLooks looks = load_liquid_looks(scene, geometry, motions);
  FF_CHECK(mesh_run(out, scene, last_frame, opt, looks, sum, progress));
  if (geometry.size() == 1 && geometry[0].skin) FF_CHECK(rig_final_mesh(out, scene, geometry[0], motions[0], time, looks, sum));
  return {};
}

/// The output folder made ready before anything is written: writable, an interrupted run's partial files removed, a
/// fresh run's old checkpoints removed, particles/ and checkpoint/ made. Inputs are all checked before it is touched.
Status prepare_out_dir(const fs::path& out, const scene::Scene& scene, const RunOptions& opt, bool resume) {
  if (opt.mesh && opt.vdb && !io::vdb_available())
    return param_error("--vdb: this build has no OpenVDB (install libopenvdb-dev and rebuild)");
  // Inputs are all checked before the output folder is touched.
  FF_CHECK(io::ensure_writable_dir(out));
  if (const auto n = io::remove_stale_temp_files(out))  // what a run or mesh killed mid-write left
    spdlog::info("removed {} partial file(s) left by an interrupted run", n);
  if (!resume) {  // a fresh run: an earlier run's checkpoints must not become this one's previous checkpoint
    std::error_code ec;
    fs::remove(checkpoint_file(out), ec);
    fs::remove(previous_checkpoint_file(out), ec);
  }
  FF_CHECK(io::ensure_writable_dir(out / "particles"));
  if (scene.output.checkpoint_every > 0) FF_CHECK(io::ensure_writable_dir(out / "checkpoint"));
  return {};
}

/// A fresh run's state: the initial particles, written as frame 0 and measured.
Status start_fresh(const fs::path& out, const scene::Scene& scene, const TargetSetup& prepared,
                   sim::ParticleSet&& initial, RunState& st) {
  st.particles = std::move(initial);
  std::vector<Vec3f> xs, vs;
  std::vector<std::uint8_t> ts, flags;
  FF_CHECK(write_frame(out, 0, st.particles, scene.output.velocity, scene.solver.spacing(), xs, vs, ts));
  FrameRow row{0, 0.0, st.particles.size(), 0.0, 0, 0, 0.0, 0.0, core::peak_rss_mib()};
  measure_frame(prepared.shapes, prepared.motions, 0.0, st.particles, scene.solver.particle_radius, 0, flags, row,
                st.target_rows);
  st.rows.push_back(row);
  return {};
}

/// --device, checked against the scene (a scene without targets runs no controller).
Result<Device> run_device(const scene::Scene& scene, bool has_targets, const std::string& name) {
  FF_TRY(const Device device, parse_device(name));
  control::ControllerSpec spec = scene.controller;
  if (!has_targets) spec.name = "none";
  FF_CHECK(check_device(device, spec));
  return device;
}

}  // namespace

// Both bounds of the default animation, measured on the default scene (200 frames, 10k particles; bench/RESULTS.md,
// "The default run's animation"): 51 meshed frames took 2.4 s against 16.6 s of simulation (+15 %, under the
// quarter the run may add) and made a 9.5 MB GLB (~0.19 MB a frame), so 60 frames stay well under 20 MB. Meshing and
// simulating both scale with the particle count, so the share holds at other sizes.
constexpr int kAnimationEvery = 4, kAnimationFrames = 60;

int animation_every(int frames) {
  return std::max(kAnimationEvery, (frames + kAnimationFrames - 1) / kAnimationFrames);
}

Result<RunSummary> run_scene(const scene::Scene& scene_in, const RunOptions& opt, core::Progress& progress) {
  const fs::path out = opt.out_dir;
  scene::Scene scene = scene_in;
  if (opt.controller) scene.controller.name = *opt.controller;
  FF_CHECK(scene.controller.validate());

  // Targets are loaded and checked first so that a bad mesh fails fast; a scene that names only its
  // targets is completed from them (spacing, fluid, domain).
  FF_TRY(auto geometry, load_target_meshes(scene));
  FF_CHECK(complete_scene(scene, geometry));
  // The device is checked before anything is sampled or written: --device gpu on a scene it does not do yet stops here.
  FF_TRY(const Device device, run_device(scene, !geometry.empty(), opt.device));
  const bool run_until_formed = !opt.frames && scene.auto_frames && !geometry.empty();
  const int frames = opt.frames.value_or(run_until_formed ? opt.max_auto_frames : scene.output.frames);
  if (!(frames >= 1 && frames <= 10'000'000))
    return param_error(fmt::format("--frames = {} is outside [1, 10000000]", frames));
  if (opt.frames) scene.output.frames = frames, scene.auto_frames = false;  // the report's scene is the run's

  // The memory the run will need, estimated and checked before anything large is allocated.
  FF_TRY(const RunEstimate estimate, check_run_budget(scene, geometry, opt.max_memory_mib));
  if (estimate.large)
    spdlog::warn("a large run: about {} fluid particles and {} control samples, ~{:.0f} MiB (limit {:.0f} MiB)",
                 estimate.fluid_particles, estimate.control_samples, estimate.memory_mib, estimate.limit_mib);

  // The fluid is made (and its size checked) before the output folder is touched.
  const bool resume = opt.resume && has_checkpoint(out);
  sim::ParticleSet initial;
  if (!resume) {
    FF_CHECK(sim::fill_sources(scene.fluid, scene.domain, scene.solver.particle_radius, initial));
    assign_targets(initial, geometry);
  }

  FF_CHECK(prepare_out_dir(out, scene, opt, resume));

  // Control particles of every target (METHOD §a.1), cached in OUT/cache by mesh content and parameters.
  FF_TRY(TargetSetup prepared, setup_targets(scene, geometry, out / "cache", out, progress));

  RunState st;
  bool resumed = false;
  if (opt.resume) {
    FF_TRY(resumed, resume_from_checkpoint(out, scene.hash, st));
  }
  if (!resumed) FF_CHECK(start_fresh(out, scene, prepared, std::move(initial), st));
  if (st.particles.size() == 0) return input_error("the scene creates no fluid particles");

  sim::PbfSolver solver(scene.solver, scene.domain);
  control::ControlContext ctx{scene.solver.particle_radius, solver.particle_mass(), scene.solver.rest_density,
                              scene.solver.gravity, scene.domain, scene.solver.support()};
  // A scene without targets has nothing to control: plain PBF whatever the controller setting.
  control::ControllerSpec spec = scene.controller;
  if (prepared.controls.empty()) spec.name = "none";
  FF_TRY(auto stepper, make_stepper(device, scene.solver, scene.domain, spec, std::move(prepared.controls), ctx, st.particles));
  spdlog::info("{} particles, d = {} m, H_p = {} m, rho0 = {:.1f} kg/m^3 (lattice-calibrated), controller {}, {}",
               st.particles.size(), scene.solver.spacing(), scene.solver.support(), solver.rest_density(),
               stepper->controller(), stepper->device() == "cpu" ? fmt::format("{} threads", core::thread_count())
                                                                 : "on " + stepper->device());

  const RunFacts facts{scene,
                       std::move(prepared.info),
                       prepared.shapes,
                       prepared.control_count,
                       std::string(stepper->controller()),
                       stepper->device(),
                       solver.rest_density(),
                       solver.particle_mass(),
                       estimate};
  progress.begin(run_until_formed ? "forming" : "simulating", static_cast<std::size_t>(frames));
  progress.tick(static_cast<std::size_t>(st.next_frame - 1));
  const FrameLoop loop{out, facts, prepared.motions, frames, run_until_formed};
  FF_TRY(const int last_frame, simulate_frames(loop, st, *stepper, progress));
  FF_CHECK(write_report(out, facts, st, "ok", ""));

  RunSummary sum = run_summary(facts, st, last_frame);
  if (opt.mesh) FF_CHECK(mesh_and_rig(out, scene, geometry, prepared.motions, last_frame, st.time, opt, sum, progress));
  FF_CHECK(write_page(out, PageSources{opt.mesh, opt.mesh && (opt.mesh_every > 0 || opt.animation)}));
  return sum;
}

}  // namespace ff::pipeline
