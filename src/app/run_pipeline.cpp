#include "app/run_pipeline.h"

#include "app/targets.h"

#include "core/memory.h"
#include "core/parallel.h"
#include "core/timer.h"
#include "io/atomic_file.h"
#include "io/load_mesh.h"
#include "io/write_ply.h"
#include "sim/checkpoint.h"
#include "sim/emitter.h"
#include "sim/pbf_solver.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include <fstream>
#include <iterator>

namespace ff::app {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

/// One row of metrics.csv (DESIGN.md output contract).
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
};

json rows_to_json(const std::vector<FrameRow>& rows) {
  json a = json::array();
  for (const auto& r : rows)
    a.push_back({r.frame, r.time, r.particles, r.step_seconds, r.substeps, r.iterations, r.density_error_mean,
                 r.density_error_max, r.peak_memory_mib});
  return a;
}

std::vector<FrameRow> rows_from_json(const json& a) {
  std::vector<FrameRow> rows;
  if (!a.is_array()) return rows;
  for (const auto& e : a)
    rows.push_back({e[0].get<int>(), e[1].get<double>(), e[2].get<std::size_t>(), e[3].get<double>(), e[4].get<int>(),
                    e[5].get<long>(), e[6].get<double>(), e[7].get<double>(), e[8].get<double>()});
  return rows;
}

std::string metrics_csv(const std::vector<FrameRow>& rows) {
  std::string s =
      "frame,time_s,particles,step_time_s,substeps,iterations,density_error_mean,density_error_max,peak_memory_mb\n";
  for (const auto& r : rows)
    s += fmt::format("{},{:.6f},{},{:.6f},{},{},{:.6g},{:.6g},{:.1f}\n", r.frame, r.time, r.particles, r.step_seconds,
                     r.substeps, r.iterations, r.density_error_mean, r.density_error_max, r.peak_memory_mib);
  return s;
}

json scene_to_json(const io::Scene& s) {
  auto v3 = [](const Vec3f& v) { return json::array({v.x(), v.y(), v.z()}); };
  json j;
  j["file"] = s.file.string();
  j["solver"] = {{"particle_radius", s.solver.particle_radius}, {"support_factor", s.solver.support_factor},
                 {"iterations", s.solver.iterations},           {"max_iterations", s.solver.max_iterations},
                 {"max_density_error", s.solver.max_density_error}, {"max_dt", s.solver.max_dt},
                 {"cfl", s.solver.cfl},                         {"max_substeps", s.solver.max_substeps},
                 {"gravity", v3(s.solver.gravity)},             {"rest_density", s.solver.rest_density},
                 {"viscosity", s.solver.viscosity},             {"vorticity", s.solver.vorticity},
                 {"epsilon", s.solver.epsilon},                 {"scorr_k", s.solver.scorr_k},
                 {"scorr_n", s.solver.scorr_n},                 {"scorr_dq", s.solver.scorr_dq}};
  j["domain"] = {{"min", v3(s.domain.min)}, {"max", v3(s.domain.max)}};
  j["fluid"] = json::array();
  for (const auto& f : s.fluid) {
    if (f.shape == sim::FluidSource::Shape::Box)
      j["fluid"].push_back({{"shape", "box"}, {"min", v3(f.min)}, {"max", v3(f.max)}, {"velocity", v3(f.velocity)}});
    else
      j["fluid"].push_back({{"shape", "sphere"}, {"center", v3(f.center)}, {"radius", f.radius}, {"velocity", v3(f.velocity)}});
  }
  j["targets"] = json::array();
  for (const auto& t : s.targets)
    j["targets"].push_back({{"mesh", t.mesh.string()}, {"scale", v3(t.transform.scale)},
                            {"rotate", v3(t.transform.rotate_deg)}, {"translate", v3(t.transform.translate)},
                            {"start", t.start}});
  j["output"] = {{"fps", s.output.fps}, {"frames", s.output.frames}, {"checkpoint_every", s.output.checkpoint_every},
                 {"velocity", s.output.velocity}};
  return j;
}

/// Mean wall-clock of the simulated frames (frame 0 is the initial state, not simulated).
double mean_step_seconds(const std::vector<FrameRow>& rows) {
  double total = 0.0;
  int n = 0;
  for (const auto& r : rows)
    if (r.frame > 0) total += r.step_seconds, ++n;
  return n ? total / n : 0.0;
}

fs::path frame_path(const fs::path& out, int frame) {
  return out / "particles" / fmt::format("frame_{:05d}.ply", frame);
}

Status write_frame(const fs::path& out, int frame, const sim::ParticleSet& p, bool velocity,
                   std::vector<Vec3f>& x, std::vector<Vec3f>& v, std::vector<std::uint8_t>& t) {
  sim::sorted_by_id(p, x, v, t);
  io::ParticleFrameView view;
  view.positions = x;
  if (velocity) view.velocities = v;
  view.targets = t;
  return io::write_particles_ply(frame_path(out, frame), view);
}

Result<std::vector<std::uint8_t>> read_bytes(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  if (!in) return input_error(fmt::format("{}: cannot read", p.string()));
  return std::vector<std::uint8_t>(std::istreambuf_iterator<char>(in), {});
}

}  // namespace

Result<RunSummary> run_scene(const io::Scene& scene, const RunOptions& opt, core::Progress& progress) {
  const fs::path out = opt.out_dir;
  const fs::path ckpt_dir = out / "checkpoint", ckpt_file = ckpt_dir / "state.ffck";
  const int frames = opt.frames.value_or(scene.output.frames);
  if (!(frames >= 1 && frames <= 10'000'000))
    return param_error(fmt::format("--frames = {} is outside [1, 10000000]", frames));

  // Targets are loaded and checked now so that a bad mesh fails fast; shape control (sampling and
  // controllers) consumes them in later stages.
  for (std::size_t i = 0; i < scene.targets.size(); ++i) {
    io::MeshLoadStats st;
    FF_TRY(auto mesh, io::load_mesh(scene.targets[i].mesh, io::LoadOptions{scene.targets[i].transform}, &st));
    spdlog::info("target {}: {} ({} vertices, {} triangles, {} degenerate dropped)", i,
                 scene.targets[i].mesh.filename().string(), mesh.vertices.size(), mesh.triangles.size(),
                 st.dropped_degenerate);
  }

  // The fluid is made (and its size checked) before the output folder is touched.
  sim::ParticleSet initial;
  if (!opt.resume || !fs::exists(ckpt_file))
    FF_CHECK(sim::fill_sources(scene.fluid, scene.domain, scene.solver.particle_radius, initial));

  // Inputs are all checked before the output folder is touched.
  FF_CHECK(io::ensure_writable_dir(out));
  FF_CHECK(io::ensure_writable_dir(out / "particles"));
  if (scene.output.checkpoint_every > 0) FF_CHECK(io::ensure_writable_dir(ckpt_dir));

  // Control particles of every target (METHOD §a.1), cached in OUT/cache by mesh content and parameters.
  // The sampling spacing defaults to the fluid spacing d (METHOD §0: d_c = d).
  sampling::SamplingParams sp = scene.sampling;
  if (!(sp.spacing > 0.0f)) sp.spacing = scene.solver.spacing();
  sp.rest_density = scene.solver.rest_density;
  json targets_json = json::array();
  std::vector<sampling::ControlSet> controls;
  for (std::size_t i = 0; i < scene.targets.size(); ++i) {
    FF_TRY(TargetControls tc, prepare_target(scene.targets[i], sp, static_cast<std::uint8_t>(i), out / "cache", progress));
    for (const auto& w : tc.report.warnings) spdlog::warn("target {}: {}", i, w);
    if (tc.from_cache)
      spdlog::info("target {}: {} control particles from the cache ({})", i, tc.set.size(), tc.cache_file.filename().string());
    else
      spdlog::info("target {}: {} control particles ({}, spacing {:g} m, {:.2f} s)", i, tc.set.size(),
                   sampling::method_name(tc.report.method), tc.report.spacing, tc.report.seconds);
    targets_json.push_back({{"mesh", scene.targets[i].mesh.string()}, {"control_particles", tc.set.size()},
                            {"spacing", tc.set.spacing}, {"cached", tc.from_cache},
                            {"controls", fs::relative(tc.cache_file, out).string()}});
    controls.push_back(std::move(tc.set));
  }
  if (!controls.empty())
    spdlog::warn("this build has no shape controller yet: targets are sampled, but the fluid runs uncontrolled");

  sim::ParticleSet particles;
  std::vector<FrameRow> rows;
  int next_frame = 1;
  double time = 0.0;
  std::vector<Vec3f> xs, vs;
  std::vector<std::uint8_t> ts;

  bool resumed = false;
  if (opt.resume && fs::exists(ckpt_file)) {
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
    if (!extra.is_discarded() && extra.contains("rows")) rows = rows_from_json(extra["rows"]);
    resumed = true;
    spdlog::info("resuming from frame {} (t = {:.4f} s, {} particles)", next_frame, time, particles.size());
  } else if (opt.resume) {
    spdlog::warn("--resume: no checkpoint in {}, starting from the beginning", ckpt_dir.string());
  }
  if (!resumed) {
    particles = std::move(initial);
    FF_CHECK(write_frame(out, 0, particles, scene.output.velocity, xs, vs, ts));
    rows.push_back({0, 0.0, particles.size(), 0.0, 0, 0, 0.0, 0.0, core::peak_rss_mib()});
  }
  if (particles.size() == 0) return input_error("the scene creates no fluid particles");

  sim::PbfSolver solver(scene.solver, scene.domain);
  sim::NoController controller;
  spdlog::info("{} particles, d = {} m, H_p = {} m, rho0 = {:.1f} kg/m^3 (lattice-calibrated), {} threads",
               particles.size(), scene.solver.spacing(), scene.solver.support(), solver.rest_density(),
               core::thread_count());

  const double frame_dt = 1.0 / scene.output.fps;
  auto write_report = [&](std::string_view status, std::string_view error) -> Status {
    json rep;
    rep["fluidform_version"] = FF_VERSION;
    rep["status"] = status;
    if (!error.empty()) rep["error"] = error;
    rep["scene"] = scene_to_json(scene);
    rep["targets"] = targets_json;
    double peak = 0.0;
    for (const auto& r : rows) peak = std::max(peak, r.peak_memory_mib);
    rep["totals"] = {{"particles", particles.size()},
                     {"frames", rows.empty() ? 0 : rows.back().frame},
                     {"simulated_seconds", rows.empty() ? 0.0 : rows.back().time},
                     {"mean_step_time_s", mean_step_seconds(rows)},
                     {"peak_memory_mb", peak},
                     {"threads", core::thread_count()},
                     {"rest_density", solver.rest_density()},
                     {"particle_mass", solver.particle_mass()}};
    FF_CHECK(io::write_file_atomic(out / "metrics.csv", metrics_csv(rows)));
    return io::write_file_atomic(out / "report.json", rep.dump(2) + "\n");
  };

  progress.begin("simulating", static_cast<std::size_t>(frames));
  progress.tick(static_cast<std::size_t>(next_frame - 1));
  bool warned_cap = false;
  for (int f = next_frame; f <= frames; ++f) {
    core::Stopwatch watch;
    auto stats = solver.advance(particles, time, frame_dt, controller);
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
    FF_CHECK(write_frame(out, f, particles, scene.output.velocity, xs, vs, ts));
    rows.push_back({f, time, particles.size(), seconds, stats->substeps, stats->times.iterations, stats->density_error_mean,
                    stats->density_error_max, core::peak_rss_mib()});
    if (scene.output.checkpoint_every > 0 && (f % scene.output.checkpoint_every == 0 || f == frames)) {
      sim::Checkpoint ck{f + 1, time, scene.hash, json{{"rows", rows_to_json(rows)}}.dump(), particles};
      FF_CHECK(io::write_file_atomic(ckpt_file, sim::encode_checkpoint(ck)));
      FF_CHECK(write_report("running", ""));
    }
    if (!progress.tick(static_cast<std::size_t>(f))) return Error{Error::Kind::Cancelled, "cancelled"};
  }
  progress.end();
  FF_CHECK(write_report("ok", ""));

  RunSummary sum;
  sum.particles = particles.size();
  sum.frames_written = frames + 1;
  sum.mean_frame_seconds = mean_step_seconds(rows);
  sum.peak_memory_mib = core::peak_rss_mib();
  return sum;
}

}  // namespace ff::app
