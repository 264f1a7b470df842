#pragma once
// What every controller checks and keeps of its targets: the samples present and weighted, one support H_c for
// all (they are sampled at one spacing), mesh swaps at increasing times, valid keyframes. Shared by `adaptive`
// and the baselines so that they accept and reject exactly the same scenes.
#include "pose/mesh_anchors.h"
#include "pose/skinning.h"
#include "control/strength.h"
#include "pose/target_motion.h"
#include "core/error.h"
#include "sampling/control_set.h"

#include <memory>
#include <string_view>
#include <vector>

namespace ff::control {

/// One target as the controllers see it: its samples (weights computed) and when it starts to act.
struct ControlTarget {
  sampling::ControlSet set;  ///< samples in the rest pose
  double start = 0.0;        ///< s; before this the target attracts nothing
  pose::TargetMotion motion;       ///< keyframes (none: static)
  StrengthTrack strength;    ///< control strength over time (no keys: 1); 0 releases the fluid
  /// Mesh swaps (morph A → B): from each time on, the target is this sample set instead (same support H_c).
  std::vector<std::pair<double, sampling::ControlSet>> swaps;
  /// A skinned, animated target (pose/skinning.h): its skin, and the weights of every sample of `set` (the
  /// first phase; swapped-in meshes are not skinned). Null: posed by `motion` alone.
  std::shared_ptr<const pose::TargetSkin> skin;
  std::vector<std::array<std::uint16_t, io::kMaxInfluences>> skin_joints;
  std::vector<std::array<float, io::kMaxInfluences>> skin_weights;
  /// The samples anchored to the posed mesh (pose/mesh_anchors.h: a sheet's to its triangles, a coarse closed
  /// mesh's in it as a cage), placed from its skinned vertices instead of by their own weights. Null: by their weights.
  std::shared_ptr<const pose::MeshAnchors> anchors;
};

/// One of a target's sample sets and the time from which it is in use (the first: −∞).
struct TargetPhase {
  double time;
  sampling::ControlSet set;
};

struct CheckedTargets {
  float hc = 0.0f;                                 ///< H_c of every set
  std::vector<std::vector<TargetPhase>> phases;    ///< per target, in time order
  std::vector<double> start;                       ///< per target, s
  std::vector<pose::TargetMotion> motion;                ///< per target
  std::vector<StrengthTrack> strength;             ///< per target
  std::vector<std::shared_ptr<const pose::TargetSkin>> skin;  ///< per target (null: not skinned)
  std::vector<std::vector<std::array<std::uint16_t, io::kMaxInfluences>>> skin_joints;  ///< per target, per sample
  std::vector<std::vector<std::array<float, io::kMaxInfluences>>> skin_weights;
  std::vector<std::shared_ptr<const pose::MeshAnchors>> anchors;  ///< per target (null: posed by the samples' weights)
  bool moving = false;                             ///< any target keyframed or skinned
};

/// Errors name `who` (the controller) and the target.
Result<CheckedTargets> validate_control_targets(std::vector<ControlTarget> targets, std::string_view who);

/// S_0 = Σ_k |g_k|² over a full resting lattice neighbourhood, g_k = (m_p/ρ_ref) ∇W_spiky(k d, H_c): what a filled
/// interior control particle sees; the scale of the density constraints' ε_c (METHOD §a.3).
double full_gradient_sum(float d, float hc, float particle_mass, double rho_ref);

}  // namespace ff::control
