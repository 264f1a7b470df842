#pragma once
// One sample set under every controller: every target's control samples (METHOD §a.1) flattened into SoA arrays and
// kept at the targets' current pose — keyframed motion, live steering (control/steering.h), mesh swaps (morph
// phases) — with their pose velocity u_c (the paper's v_c), optionally sorted by cell for locality, optionally with
// the boundary normals of eq. 16. `adaptive` and every baseline hold one, so they see the same samples at the same
// pose and accept and reject the same scenes (validate_control_targets).
#include "control/control_targets.h"
#include "pose/skinning.h"
#include "pose/target_motion.h"
#include "core/error.h"
#include "core/types.h"

#include <array>
#include <cstdint>
#include <memory>
#include <string_view>
#include <vector>

namespace ff::control {

struct SampleOptions {
  bool cell_order = false;  ///< sort the samples by their cell of edge H_c (z-major), so pair loops walk memory in order
  bool weights = true;      ///< phi = φ̃ of each sample (false: 1 everywhere)
  bool normals = false;     ///< compute normal = −Σ_j m_c ∇W_spiky(x_i − x_j, H_c) over the same target, and g_ref
  bool velocities = false;  ///< compute u_c of moving targets by a forward difference over the sub-step
};

class ControlSamples {
 public:
  /// Checks the targets (control_targets.h; errors name `who`) and flattens each target's first phase.
  Status init(std::vector<ControlTarget> targets, std::string_view who, const SampleOptions& options);
  /// The samples at `time`: a target whose mesh swaps at this time takes its next sample set (true is returned:
  /// indices of the previous set are then invalid), moving targets are posed, and with velocities, u_c over `dt`.
  bool update(double time, float dt);
  /// Whether update(time) would take some target's next sample set (a device run ends its submission there).
  bool swaps_by(double time) const {
    for (std::size_t t = 0; t < phases_.size(); ++t)
      if (current_[t] + 1 < phases_[t].size() && time >= phases_[t][current_[t] + 1].time) return true;
    return false;
  }
  /// Target `t` holds `pose` from the next update() on (live steering), replacing its keyframes.
  void set_target_pose(std::size_t t, const pose::Pose& pose);

  std::size_t size() const { return position.size(); }
  std::size_t targets() const { return phases_.size(); }
  /// Target `t`'s control strength at `at`: 0 before its start, else its track's value (control/strength.h).
  float strength(std::uint8_t t, double at) const {
    return t < start_.size() && at >= start_[t] ? strength_[t].at(at) : 0.0f;
  }
  /// Whether target `t` acts at all at `at` (started, strength above 0): a target that does not adds nothing.
  bool acting(std::uint8_t t, double at) const { return strength(t, at) > 0.0f; }
  bool moving() const { return moving_; }
  /// Whether target `t` moves (keyframes, a skin, or a live pose): its samples have a pose velocity u_c.
  bool moving(std::uint8_t t) const {
    return t < motion_.size() && (motion_[t].moving() || (skin_[t] && current_[t] == 0));
  }

  float hc = 0.0f;  ///< H_c of every sample
  // Flattened samples of every target's current phase.
  std::vector<Vec3f> position, velocity;  ///< x_c at the current pose; u_c (0 when static or without velocities)
  std::vector<float> rho_c;               ///< ρ_c,i (eq. 9)
  std::vector<float> phi;                 ///< φ̃_i (eq. 1–4), or 1 without weights
  std::vector<std::uint8_t> target;       ///< target of each sample
  std::vector<Index> original;            ///< index in the targets' concatenated sets (what bound_control reports)
  std::vector<Vec3f> normal;              ///< with normals: outward n at each sample (eq. 16), posed
  std::vector<float> mass;                ///< m_c per target
  float g_ref = 0.0f;                     ///< with normals: max |n| over the samples (eq. 15 threshold)

 private:
  void flatten();
  void pose(double time, float dt);
  SampleOptions options_;
  std::vector<std::vector<TargetPhase>> phases_;  // per target: its sample sets in time order
  std::vector<std::size_t> current_;             // per target: the phase in use
  std::vector<double> start_;
  std::vector<StrengthTrack> strength_;
  std::vector<pose::TargetMotion> motion_;
  std::vector<std::shared_ptr<const pose::TargetSkin>> skin_;  // per target, null: not skinned
  std::vector<std::vector<std::array<std::uint16_t, io::kMaxInfluences>>> target_joints_;  // per target, per sample
  std::vector<std::vector<std::array<float, io::kMaxInfluences>>> target_weights_;
  // Flattened like position: each sample's influences (zero weights for samples of unskinned targets or phases).
  std::vector<std::array<std::uint16_t, io::kMaxInfluences>> joints_;
  std::vector<std::array<float, io::kMaxInfluences>> weights_;
  std::vector<std::uint8_t> skinned_;  // per flattened sample: its target's current phase is skinned
  std::vector<std::shared_ptr<const pose::MeshAnchors>> anchors_;  // per target, null: posed by the samples' weights
  std::vector<Index> anchor_;          // per flattened sample: its index in its target's anchors (or kInvalidIndex)
  std::vector<std::vector<Vec3f>> now_vertices_, next_vertices_;  // per anchored target, scratch of pose()
  std::vector<pose::PosedJoints> now_joints_, next_joints_;  // per target, scratch of pose()
  bool moving_ = false;
  double time_ = 0.0;
  std::vector<Vec3f> rest_position_, rest_normal_;  // the rest pose of position and normal (moving targets)
};

}  // namespace ff::control
