#pragma once
// What the baselines (METHOD.md §b) share: every target's control samples flattened into SoA arrays, kept at
// the targets' current pose (keyframed motion, mesh swaps), their velocities u_c, and the sample ↔ fluid pairs
// within a radius, found once per sub-step. The baselines run in the same harness as `adaptive` (same samples,
// same solver, same per-target rule: a fluid particle only feels the samples of its own target, and only once
// that target has started), so the table compares control laws and nothing else.
#include "control/control_samples.h"
#include "control/control_targets.h"
#include "control/control_context.h"
#include "core/neighbor_grid.h"
#include "core/fields.h"
#include "sim/particle_set.h"

#include <string_view>
#include <vector>

namespace ff::control {

class BaselineCore {
 public:
  /// Checks the targets as `adaptive` does (samples present, one support H_c); `who` names the controller.
  Status init(std::vector<ControlTarget> targets, const ControlContext& ctx, std::string_view who);

  /// Moves the samples to their pose at `time` (u_c from the pose at time + dt) and applies mesh swaps.
  /// True when a swap changed the sample set (indices of the previous set are then invalid).
  bool update(double time, float dt);
  /// Live steering (control/steering.h, the controllers forward to this): target `t` holds `pose` from the next
  /// update() on (ControlSamples keeps every target's rest pose, so a static target can start moving).
  void set_target_pose(std::size_t t, const pose::Pose& pose);
  /// Sample → fluid pairs within r (near_fluid), on the fluid positions x; r ≤ the radius given to init.
  void sample_to_fluid(const sim::ParticleSet& p, float r);
  /// Fluid → sample pairs within r (near_samples), on the fluid positions x.
  void fluid_to_sample(const sim::ParticleSet& p, float r);

  /// Whether fluid particle j (target tj) and sample i interact: same target, and the target acts (it has started
  /// and its strength is above 0; the baselines do not soften between 0 and 1).
  bool pairs(std::uint8_t tj, Index i) const { return samples.target[i] == tj && live[tj]; }
  bool live_target(std::uint8_t t) const { return t < live.size() && live[t]; }

  ControlContext ctx;
  float hc = 0.0f;   ///< H_c, the samples' support (the same for every target)
  float d = 0.0f;    ///< fluid spacing
  /// Every target's current samples (index = bound_control's "flattened index"): position, velocity u_c, ρ_c, target.
  ControlSamples samples;
  std::vector<std::uint8_t> live;  ///< per target: acting at the current time (started, strength > 0)
  core::NeighborList near_fluid;    ///< sample → fluid pairs within the radius of the last sample_to_fluid
  core::NeighborList near_samples;  ///< fluid → sample pairs within the radius of the last fluid_to_sample
  double time = 0.0;

 private:
  core::NeighborGrid fluid_grid_{1.0f}, sample_grid_{1.0f};
  bool sample_grid_valid_ = false;
};

}  // namespace ff::control
