#pragma once
// The part of a run's start that `fluidform run` and `fluidform serve` share: every target's control particles
// (sampled or from the cache), its metric shapes over time (mesh swaps included) and its motion; and the
// per-frame shape metrics of all targets, N_c-weighted into one row. Factored out of run_pipeline.cpp so that
// the live viewer (app/live_scene.h) steps exactly the scene a run would.
#include "pipeline/auto_scene.h"
#include "control/control_targets.h"
#include "pose/skinned_target.h"
#include "pose/target_motion.h"
#include "core/error.h"
#include "core/progress.h"
#include "scene/scene.h"
#include "metrics/shape_metrics.h"
#include "sim/particle_set.h"

#include <nlohmann/json.hpp>

#include <array>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace ff::pipeline {

/// A target's shapes over time: its mesh, then each swapped-in mesh from its time on.
struct TargetShapes {
  std::vector<double> from;  // from[0] = −∞
  std::vector<metrics::TargetShape> shape;
  /// A skinned target's first phase is measured against its posed mesh: the bind mesh and samples with their skin
  /// (pose/skinned_target.h), posed at each measured time and given a shape of their own (posed_shape).
  using Skinned = pose::SkinnedTarget;
  std::optional<Skinned> skinned;
  const metrics::TargetShape& at(double t) const {
    std::size_t k = 0;
    while (k + 1 < from.size() && t >= from[k + 1]) ++k;
    return shape[k];
  }
};

/// The sampling parameters of a scene's targets: the scene's, with the spacing defaulting to the fluid spacing d
/// (METHOD §0: d_c = d) and the controls calibrated to the fluid's rest density.
sampling::SamplingParams target_sampling(const scene::Scene& scene);

/// Target `t` of `scene` as another mesh (a morph's, or the live viewer's swap): its control particles, sampled
/// with the target's transform (or from `cache_dir`), and its metric shape. Errors of loading the mesh or building
/// the shape are prefixed with `where` (when not empty).
struct MeshPhase {
  sampling::ControlSet set;
  metrics::TargetShape shape;
};
Result<MeshPhase> prepare_mesh(const scene::Scene& scene, std::size_t t, const std::filesystem::path& mesh,
                               const std::filesystem::path& cache_dir, core::Progress& progress,
                               const std::string& where = "");

/// Every target of a completed scene, ready for make_controller and the metrics.
struct TargetSetup {
  std::vector<control::ControlTarget> controls;  ///< handed to make_controller (moved out)
  std::vector<TargetShapes> shapes;
  std::vector<pose::TargetMotion> motions;
  nlohmann::json info = nlohmann::json::array();  ///< report.json "targets" (control file paths relative to report_dir)
  std::size_t control_count = 0;                  ///< samples of every target's first phase
};

/// Samples (or loads from `cache_dir`) every target of `scene` (completed by complete_scene, `geometry` from
/// load_target_meshes) and its mesh swaps. Errors name the target.
Result<TargetSetup> setup_targets(const scene::Scene& scene, const std::vector<TargetGeometry>& geometry,
                                        const std::filesystem::path& cache_dir,
                                        const std::filesystem::path& report_dir, core::Progress& progress);

/// A skinned target's metric shape at `time`, as every measured frame takes it: its mesh and samples skinned, then
/// posed by `pose` (its keyframes); the signed distance is the posed mesh's own, exact (metrics::TargetShape::posed).
/// `bind`: the target's shape at the bind pose (TargetShapes::shape[0]).
Result<metrics::TargetShape> posed_shape(const metrics::TargetShape& bind, const TargetShapes::Skinned& skinned,
                                         const pose::Pose& pose, double time);
/// The same shape rebuilt from the posed mesh (its own SDF grid and winding numbers: ~2 s for the 9k-sample character):
/// the reference posed_shape is measured against.
Result<metrics::TargetShape> posed_shape_rebuilt(const TargetShapes::Skinned& skinned, const pose::Pose& pose, double time);

/// The N_c-weighted shape metrics of one frame, and each target's own.
struct ShapeMeasure {
  std::size_t controlled = 0;
  double error_rate = 0, e_fwd = 0, e_bwd = 0, e_fwd_all = 0, inside = 0, splash = 0;
  std::vector<metrics::FrameMetrics> per_target;
};

/// Measures every target at `time`, each in its rest frame (the fluid mapped into it by the inverse of the pose
/// `motions[t].at(time)`). `controlled` is scratch. No targets: an empty measure.
ShapeMeasure measure_targets(const std::vector<TargetShapes>& shapes, const std::vector<pose::TargetMotion>& motions,
                             double time, const sim::ParticleSet& p, float r, std::vector<std::uint8_t>& controlled);

}  // namespace ff::pipeline
