#pragma once
// A scene stepped one frame at a time, for the live viewer (`fluidform serve SCENE.json`): loaded, completed
// and sampled exactly as `fluidform run` does (app/scene_setup.h), then steered between frames — a target moved or
// rotated (control/steering.h), its mesh swapped for another of the scene's meshes, the controller switched, the run
// restarted. Not thread-safe: one thread (the server's simulation thread) owns it.
#include "pipeline/auto_scene.h"
#include "pipeline/scene_setup.h"
#include "pipeline/stepper.h"
#include "control/registry.h"
#include "pose/target_motion.h"
#include "core/error.h"
#include "core/progress.h"
#include "io/triangle_mesh.h"
#include "scene/scene.h"
#include "sim/particle_set.h"
#include "sim/pbf_solver.h"

#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace ff::pipeline {

struct LiveOptions {
  std::filesystem::path cache_dir = "fluidform-out/cache";  ///< control-particle cache (shared with `run`'s default)
  std::optional<std::string> controller;                    ///< overrides scene.controller.name
  std::vector<std::filesystem::path> extra_meshes;          ///< more meshes for the swap list (sampled when chosen)
  std::optional<double> max_memory_mib;                     ///< --max-memory: overrides scene.limits.max_memory_mb
  std::string device = "cpu";  ///< --device cpu|gpu|auto (pipeline/stepper.h): where the frames are simulated
};

/// What one step reports (the viewer's HUD).
struct LiveFrame {
  int frame = 0;
  double time = 0.0;          ///< s simulated, end of the frame
  double step_seconds = 0.0;  ///< wall-clock of the frame's sub-steps
  int substeps = 0;
  std::size_t controlled = 0;
  double error_rate = NAN;    ///< %, N_c-weighted over the targets, each against its current (steered) pose; NaN: none
  double inside = NAN, splash = NAN;  ///< fractions of the targets' fluid, N_c-weighted (metrics::FrameMetrics)
  double e_fwd_all = NAN;             ///< m, E_fwd over all of the targets' fluid
};

/// A target's pose as the viewer edits it: about the target's pivot (its rest bounding-box centre).
struct LivePose {
  Vec3f translate{Vec3f::Zero()};   ///< m
  Vec3f rotate_deg{Vec3f::Zero()};  ///< degrees about x, y, z (R = R_z R_y R_x)
  float scale = 1.0f;
};

struct LiveTarget {
  std::size_t mesh = 0;  ///< index into LiveScene::meshes()
  Vec3f pivot{Vec3f::Zero()};
  Aabb box;              ///< rest pose, world
  LivePose pose;
};

/// The fluid's particles (sim::ParticleSet), as the front ends name them.
using Particles = sim::ParticleSet;

class LiveScene {
 public:
  static Result<std::unique_ptr<LiveScene>> create(const scene::Scene& scene, const LiveOptions& options,
                                                   core::Progress& progress);

  /// Advances one frame of 1/fps s; with `measure`, the frame's shape metrics too (else they stay NaN). Errors: the
  /// solver's (a non-finite particle).
  Result<LiveFrame> step(bool measure = true);
  /// The fluid back to its initial state at t = 0, the controller rebuilt (poses and meshes kept).
  Status restart();
  /// Switches the controller (a registry name), keeping the fluid where it is.
  Status set_controller(const std::string& name);
  /// Moves target `t` (its samples from the next sub-step; the metrics against the moved target). The pose is
  /// clamped so that the target's centre stays inside the domain; returns the pose applied.
  Result<LivePose> set_pose(std::size_t t, const LivePose& pose);
  /// Target `t` becomes meshes()[mesh] (sampled with the target's transform, cached like a run's targets).
  Status set_mesh(std::size_t t, std::size_t mesh, core::Progress& progress);

  const sim::ParticleSet& particles() const { return particles_; }
  /// Hands over the particles' arrays as they are and keeps an equal copy to step on: whoever holds views of
  /// particles()' buffers (the Python module's zero-copy arrays) keeps valid, unchanging data after the next step.
  sim::ParticleSet detach_particles() {
    sim::ParticleSet out = particles_;
    std::swap(out, particles_);
    return out;
  }
  /// The particles in id order (the order of a run's PLY frames), stable from frame to frame: the solver keeps
  /// them in cell order, which changes between frames.
  void particles_by_id(std::vector<Vec3f>& x, std::vector<Vec3f>& v, std::vector<std::uint8_t>& target) const {
    sim::sorted_by_id(particles_, x, v, target);
  }
  /// The current particles reconstructed into the mesh the viewer shows (the scene's spacing, surface defaults).
  Result<io::TriangleMesh> surface() const;
  const std::vector<LiveTarget>& targets() const { return targets_; }
  /// The scene's meshes: every target's and every mesh swap's, once each, then LiveOptions::extra_meshes.
  const std::vector<std::filesystem::path>& meshes() const { return meshes_; }
  std::string controller_name() const;
  /// What simulates: "cpu", or the GPU's name and driver (--device).
  std::string device() const { return gpu_ ? gpu_->device() : "cpu"; }
  const scene::Scene& scene() const { return scene_; }
  double time() const { return time_; }
  int frame() const { return frame_; }
  double fps() const { return scene_.output.fps; }

 private:
  LiveScene() = default;
  Status rebuild_controller();

  scene::Scene scene_;
  LiveOptions options_;
  std::vector<TargetGeometry> geometry_;
  std::vector<control::ControlTarget> controls_;  // master copy: a controller is made from a copy
  std::vector<TargetShapes> shapes_;
  std::vector<pose::TargetMotion> motions_;    // with the live poses (TargetMotion::live)
  std::vector<LiveTarget> targets_;
  std::vector<std::filesystem::path> meshes_;
  sim::ParticleSet initial_, particles_;
  std::unique_ptr<sim::PbfSolver> solver_;
  control::ControlContext ctx_;
  std::unique_ptr<sim::Controller> controller_;
  // --device gpu, or auto where it found a GPU: the frames are stepped on the device instead, by a stepper made
  // afresh (from the particles where they are) whenever the controller is (controller_ then stays empty).
  Device device_ = Device::Cpu;
  std::unique_ptr<FrameStepper> gpu_;
  std::vector<std::uint8_t> scratch_;
  double time_ = 0.0;
  int frame_ = 0;
};

}  // namespace ff::pipeline
