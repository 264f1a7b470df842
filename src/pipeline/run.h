#pragma once
// Drives the stages for `fluidform run`: the only place where scene, meshes, solver and writers meet.
#include "core/error.h"
#include "core/progress.h"
#include "metrics/summary.h"
#include "scene/scene.h"

#include <filesystem>
#include <optional>
#include <string>

namespace ff::pipeline {

struct RunOptions {
  std::filesystem::path out_dir = "fluidform-out";
  std::optional<int> frames;  ///< overrides scene.output.frames
  bool resume = false;        ///< continue from OUT/checkpoint/ if present
  std::optional<std::string> controller;  ///< overrides scene.controller.name
  int max_auto_frames = 600;  ///< cap of a run that stops once the shape has formed (no --frames, no output.frames)
  bool mesh = true;           ///< reconstruct the last frame into OUT/mesh/final.obj
  int mesh_every = 0;         ///< > 0: also every k-th frame → OUT/mesh/frame_NNNNN.obj, animation.glb, particles.pc2
  std::optional<double> max_memory_mib;  ///< --max-memory: overrides scene.limits.max_memory_mb
  bool animation = true;      ///< with `mesh` and no mesh_every: OUT/animation.glb of every animation_every()-th
                              ///< frame and the point cache OUT/particles.pc2 (no per-frame OBJs)
  bool vdb = false;           ///< with `mesh`: each meshed frame's level set as OUT/vdb/frame_NNNNN.vdb (OpenVDB)
  std::string device = "cpu"; ///< --device cpu|gpu|auto (pipeline/stepper.h): where the frames are simulated
};

/// The frame step of the default animation of a run of `frames` frames: every kAnimationEvery-th frame, coarser
/// for long runs so that at most kAnimationFrames are meshed, plus the last frame when the step misses it (run.cpp
/// says how both were measured). `frames` counts the particle frames, frame 0 included.
int animation_every(int frames);

/// What a finished run reports to the CLI.
struct RunSummary {
  std::size_t particles = 0;
  int frames_written = 0;
  double mean_frame_seconds = 0.0;
  double peak_memory_mib = 0.0;
  std::string controller;
  std::string device = "cpu";  ///< what simulated: "cpu", or the GPU's name and driver
  // Shape metrics (METHOD §d), when the scene has targets.
  bool has_targets = false;
  std::size_t control_particles = 0, controlled = 0;
  /// time_to_form: s from which the shape stayed formed by `formed`'s thresholds to the end; NaN: it was not formed
  /// at the end.
  double error_rate = 0, inside_fraction = 0, splash_fraction = 0, time_to_form = 0, e_fwd_all = 0, error_spacings = 0;
  metrics::FormedThresholds formed;
  // Meshing (when RunOptions::mesh).
  std::size_t mesh_triangles = 0, mesh_frames = 0;
  bool mesh_ok = false;
  bool mesh_uvs = false;  ///< the meshes wear their target's texture through UVs (else vertex colours, or none)
  double mesh_seconds = 0.0;
  bool rigged = false;  ///< OUT/rigged.glb written (one skinned target)
};

/// Runs the scene into `options.out_dir`. Everything already written stays valid on any error.
Result<RunSummary> run_scene(const scene::Scene& scene, const RunOptions& options, core::Progress& progress);

}  // namespace ff::pipeline
