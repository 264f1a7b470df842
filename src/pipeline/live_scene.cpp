#include "pipeline/live_scene.h"

#include "pipeline/run_budget.h"
#include "pipeline/target_cache.h"
#include "control/steering.h"
#include "core/timer.h"
#include "io/atomic_file.h"
#include "sim/emitter.h"
#include "surface/reconstruct.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>

namespace ff::pipeline {
namespace fs = std::filesystem;

Result<std::unique_ptr<LiveScene>> LiveScene::create(const scene::Scene& scene_in, const LiveOptions& options,
                                                     core::Progress& progress) {
  std::unique_ptr<LiveScene> s(new LiveScene());
  s->scene_ = scene_in;
  s->options_ = options;
  if (options.controller) s->scene_.controller.name = *options.controller;
  FF_CHECK(s->scene_.controller.validate());
  if (s->scene_.targets.empty()) return input_error("serve: the scene has no targets to form");
  FF_TRY(s->device_, parse_device(options.device));
  FF_CHECK(check_device(s->device_, s->scene_.controller));
  if (s->device_ == Device::Auto && !auto_finds_gpu()) {  // decided once, not at every restart or switch
    spdlog::info("--device auto: no discrete or integrated GPU, running on the CPU");
    s->device_ = Device::Cpu;
  }
  FF_TRY(s->geometry_, load_target_meshes(s->scene_));
  // A live preview keeps sampling.auto_count (10k: display rate on two cores) where `run` would raise it for thin
  // walls (~40k for the bunny, ~3 frames a second): the thin-wall line still says what would resolve them.
  s->scene_.auto_resolution = false;
  FF_CHECK(complete_scene(s->scene_, s->geometry_));
  // The memory it will need, checked (as `run` does) before the fluid, the samples or any grid is allocated.
  FF_TRY(const RunEstimate estimate, check_run_budget(s->scene_, s->geometry_, options.max_memory_mib));
  if (estimate.large)
    spdlog::warn("a large scene: about {} fluid particles and {} control samples, ~{:.0f} MiB (limit {:.0f} MiB)",
                 estimate.fluid_particles, estimate.control_samples, estimate.memory_mib, estimate.limit_mib);
  FF_CHECK(sim::fill_sources(s->scene_.fluid, s->scene_.domain, s->scene_.solver.particle_radius, s->initial_));
  assign_targets(s->initial_, s->geometry_);
  if (s->initial_.size() == 0) return input_error("the scene creates no fluid particles");
  FF_CHECK(io::ensure_writable_dir(options.cache_dir));
  (void)io::remove_stale_temp_files(options.cache_dir);  // a serve killed while it wrote the cache
  FF_TRY(TargetSetup prepared, setup_targets(s->scene_, s->geometry_, options.cache_dir, options.cache_dir, progress));
  s->controls_ = std::move(prepared.controls);
  s->shapes_ = std::move(prepared.shapes);
  s->motions_ = std::move(prepared.motions);
  auto mesh_index = [&](const fs::path& m) {
    const auto it = std::find(s->meshes_.begin(), s->meshes_.end(), m);
    if (it != s->meshes_.end()) return static_cast<std::size_t>(it - s->meshes_.begin());
    s->meshes_.push_back(m);
    return s->meshes_.size() - 1;
  };
  for (std::size_t t = 0; t < s->scene_.targets.size(); ++t) {
    LiveTarget lt;
    lt.mesh = mesh_index(s->scene_.targets[t].mesh);
    lt.pivot = s->motions_[t].pivot;
    lt.box = s->geometry_[t].box;
    s->targets_.push_back(lt);
    for (const auto& sw : s->scene_.targets[t].swaps) mesh_index(sw.mesh);
  }
  for (const auto& m : options.extra_meshes) {
    if (!fs::is_regular_file(m)) return input_error(fmt::format("--mesh {}: no such file", m.string()));
    mesh_index(m);
  }
  s->particles_ = s->initial_;
  s->solver_ = std::make_unique<sim::PbfSolver>(s->scene_.solver, s->scene_.domain);
  s->ctx_ = control::ControlContext{s->scene_.solver.particle_radius, s->solver_->particle_mass(),
                                    s->scene_.solver.rest_density,    s->scene_.solver.gravity,
                                    s->scene_.domain,                 s->scene_.solver.support()};
  FF_CHECK(s->rebuild_controller());
  return s;
}

Status LiveScene::rebuild_controller() {
  // The controller gets the targets as they are now: swapped meshes, steered poses (TargetMotion::live).
  std::vector<control::ControlTarget> targets = controls_;
  for (std::size_t t = 0; t < targets.size(); ++t) targets[t].motion = motions_[t];
  if (device_ != Device::Cpu) {
    FF_TRY(auto s, make_stepper(device_, scene_.solver, scene_.domain, scene_.controller, targets, ctx_, particles_));
    if (s->device() != "cpu") {
      gpu_ = std::move(s);
      controller_.reset();
      return {};
    }
    // auto with a controller the GPU path does not have (make_stepper said so): this one runs on the CPU.
  }
  FF_TRY(auto c, control::make_controller(scene_.controller, std::move(targets), ctx_));
  controller_ = std::move(c);
  gpu_.reset();
  return {};
}

std::string LiveScene::controller_name() const {
  return std::string(gpu_ ? gpu_->controller() : controller_->name());
}

Result<LiveFrame> LiveScene::step(bool measure) {
  const double frame_dt = 1.0 / scene_.output.fps;
  core::Stopwatch watch;
  FF_TRY(auto stats, gpu_ ? gpu_->advance(particles_, time_, frame_dt)
                          : solver_->advance(particles_, time_, frame_dt, *controller_));
  LiveFrame f;
  f.step_seconds = watch.seconds();
  ++frame_;
  time_ = frame_ * frame_dt;  // as `run` counts time (no drift of a sum), so a stepped scene matches a run's frames
  f.frame = frame_;
  f.time = time_;
  f.substeps = stats.substeps;
  if (!measure) return f;
  const ShapeMeasure m = measure_targets(shapes_, motions_, time_, particles_, scene_.solver.particle_radius, scratch_);
  f.controlled = m.controlled;
  f.error_rate = m.error_rate;
  f.inside = m.inside, f.splash = m.splash, f.e_fwd_all = m.e_fwd_all;
  return f;
}

Status LiveScene::restart() {
  particles_ = initial_;
  time_ = 0.0;
  frame_ = 0;
  // A fresh solver and controller: neither keeps state of the old run (springs, sub-step sizes).
  solver_ = std::make_unique<sim::PbfSolver>(scene_.solver, scene_.domain);
  return rebuild_controller();
}

Status LiveScene::set_controller(const std::string& name) {
  if (!control::find_controller(name))
    return param_error(fmt::format("controller {} is not one of: {}", name, control::controller_names()));
  const std::string old = scene_.controller.name;
  scene_.controller.name = name;
  if (auto st = rebuild_controller(); !st.ok()) {
    scene_.controller.name = old;
    return st;
  }
  // A controller's bonds from the old one mean nothing to the new one.
  std::fill(particles_.bound_control.begin(), particles_.bound_control.end(), kInvalidIndex);
  return {};
}

Result<LivePose> LiveScene::set_pose(std::size_t t, const LivePose& in) {
  if (t >= targets_.size()) return param_error(fmt::format("target {} does not exist ({} targets)", t, targets_.size()));
  auto finite = [](const Vec3f& v) { return v.allFinite(); };
  if (!finite(in.translate) || !finite(in.rotate_deg) || !std::isfinite(in.scale))
    return param_error("a target pose must be finite");
  LivePose p = in;
  p.scale = std::clamp(p.scale, 0.25f, 4.0f);
  for (int a = 0; a < 3; ++a) p.rotate_deg[a] = std::clamp(p.rotate_deg[a], -3600.0f, 3600.0f);
  // The target's centre stays in the domain: beyond it no fluid can follow, and the sample grids cover the domain.
  const Vec3f lo = scene_.domain.min - targets_[t].pivot, hi = scene_.domain.max - targets_[t].pivot;
  p.translate = p.translate.cwiseMax(lo).cwiseMin(hi);
  const pose::Pose pose = pose::make_pose(p.translate, p.rotate_deg, p.scale);
  if (gpu_) FF_CHECK(gpu_->set_target_pose(t, pose));  // first: its upload may fail, and then nothing has moved
  else if (auto* s = control::steerable(*controller_)) s->set_target_pose(t, pose);
  motions_[t].live = pose;
  targets_[t].pose = p;
  return p;
}

Status LiveScene::set_mesh(std::size_t t, std::size_t mesh, core::Progress& progress) {
  if (t >= targets_.size()) return param_error(fmt::format("target {} does not exist ({} targets)", t, targets_.size()));
  if (mesh >= meshes_.size()) return param_error(fmt::format("mesh {} does not exist ({} meshes)", mesh, meshes_.size()));
  if (targets_[t].mesh == mesh) return {};
  FF_TRY(MeshPhase phase, prepare_mesh(scene_, t, meshes_[mesh], options_.cache_dir, progress));
  // The swapped-in mesh replaces the target for good (its scheduled swaps are dropped); the pivot stays, so the
  // new mesh takes the target's place and pose.
  controls_[t].set = std::move(phase.set);
  controls_[t].swaps.clear();
  controls_[t].start = 0.0;
  shapes_[t].from = {-INFINITY};
  shapes_[t].shape.clear();
  shapes_[t].shape.push_back(std::move(phase.shape));
  targets_[t].mesh = mesh;
  FF_CHECK(rebuild_controller());
  spdlog::info("target {} is now {} ({} control particles)", t, meshes_[mesh].filename().string(), controls_[t].set.size());
  return {};
}

Result<io::TriangleMesh> LiveScene::surface() const {
  return surface::reconstruct(particles_.position, scene_.solver.spacing(), surface::SurfaceParams{});
}

}  // namespace ff::pipeline
