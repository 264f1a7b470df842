#pragma once
// A skinned target bound at its bind pose, and posed at any time: the bind mesh and control samples with their skin
// weights (pose/skin_weights.h), or the samples anchored to the posed mesh (pose/mesh_anchors.h, with the cage's guard
// of pose/cage_guard.h); then, at a time t, the mesh's vertices and the samples posed exactly as the controllers pose
// them. The metrics (pipeline/scene_setup.h: posed_shape) and the tests take the posed mesh and samples from here.
#include "core/error.h"
#include "core/types.h"
#include "io/skin.h"
#include "io/triangle_mesh.h"
#include "pose/mesh_anchors.h"
#include "pose/skinning.h"
#include "pose/target_motion.h"
#include "sampling/mesh_field.h"

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

namespace ff::pose {

/// At most 64 Mi cage weights (256 MiB) for one target's samples: a finer cage is not taken by SampleFollow::Auto.
inline constexpr std::size_t kMaxCageWeights = std::size_t{64} << 20;

/// A skinned target's bind pose: its skin, the bind mesh with its vertices' influences, and the control samples with
/// theirs (or anchored to the mesh).
struct SkinnedTarget {
  std::shared_ptr<const TargetSkin> skin;
  io::TriangleMesh bind_mesh;
  std::vector<std::array<std::uint16_t, io::kMaxInfluences>> mesh_joints;
  std::vector<std::array<float, io::kMaxInfluences>> mesh_weights;
  std::vector<Vec3f> bind_samples;
  std::vector<std::array<std::uint16_t, io::kMaxInfluences>> sample_joints;
  std::vector<std::array<float, io::kMaxInfluences>> sample_weights;
  float spacing = 0.0f;
  /// The bind mesh's field, which the metrics move to each pose (MeshField::moved).
  std::shared_ptr<const sampling::MeshField> bind_field;
  /// The samples anchored to the posed mesh (pose/mesh_anchors.h), as the controllers pose them. Null: the samples
  /// are skinned by sample_joints/sample_weights.
  std::shared_ptr<const MeshAnchors> anchors;
};

/// Binds target `index` (for its log lines and errors) with skin `skin`, mesh `mesh` (its `field`) and control
/// samples `samples` of spacing `spacing`: the samples' skin weights (spec.weights), and when they follow the posed
/// mesh (spec.follow: an open sheet on its triangles, a coarse closed mesh as a cage, its guard from kGuardPoses
/// poses of the clip) their anchors. Errors of anchoring name the target.
Result<SkinnedTarget> bind_skinned_target(std::size_t index, const std::shared_ptr<const TargetSkin>& skin,
                                          const io::TriangleMesh& mesh, const sampling::MeshField& field,
                                          const std::vector<Vec3f>& samples, float spacing);

/// The joints of `skin` at scene time `time`, ready to skin points by `method`.
PosedJoints joints_at(const TargetSkin& skin, double time, SkinningMethod method);

/// The bind mesh's vertices and the samples skinned by `joints`, then moved by `pose` (none: skinned only). Samples
/// anchored to the mesh are placed from the skinned vertices: the very ones the posed mesh has.
struct SkinnedPose {
  std::vector<Vec3f> vertices, samples;
};
SkinnedPose skin_pose(const SkinnedTarget& target, const PosedJoints& joints, const Pose* pose);

/// A skinned target's samples at `time` (no keyframed pose) as the controllers pose them, skinned by `method`.
std::vector<Vec3f> posed_samples(const SkinnedTarget& target, double time, SkinningMethod method);

}  // namespace ff::pose
