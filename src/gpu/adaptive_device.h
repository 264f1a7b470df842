#pragma once
// The paper's controller (control/adaptive.h, METHOD.md §a.2–§a.6) on the device, recorded into PbfDevice's
// sub-steps (issue 45). Per sub-step, on the grid of the fluid at x:
//   begin          per sample: ρ_p at x, the fill ratio and the bond radius H_c* (ctl_fill); per fluid particle: its
//                  nearest bonded sample, i.e. whether it is controlled (ctl_bonds)
//   accelerations  boundary correction and speed limit of controlled fluid (ctl_accel)
//   each sweep     the spring in the first (ctl_spring); per sample λ of the unilateral density constraint at x*
//                  (ctl_lambda); per controlled particle Δx over its bonds (ctl_correct)
// Bonds are never stored: a particle's bonds are the samples of its target within H_c*,i of it at the start of the
// sub-step, and the passes that walk them find them again in the samples' grid (the same cells as the fluid's).
// Every pass is a gather in a fixed order, so two runs give the same bits.
//
//   gather         (AdaptiveParams::gather) at the start, per target and cell of a coarse field, the nearest seed
//                  (an under-filled sample) by jump flooding (ctl_seed_init, ctl_seed_flood); with the
//                  accelerations, unbonded fluid is steered toward its cell's seed (ctl_gather)
//
// Moving targets (keyframed, steered or skinned) are posed on the host by the same control::ControlSamples the CPU
// controller uses, every sub-step of a submission at once before it is recorded (prepare_frame); each sub-step
// copies its pose into the samples' buffers and sorts them into their grids again on the device.
//
// Strength tracks and late starts (control/strength.h, ControlTarget::start): each target's strength at every sub-step
// of a frame is computed on the host by the same ControlSamples::strength (0 before the start) and copied in with the
// pose; every part of the control scales with it, and at 0 a target has no bonds, seeds or corrections (as the CPU's).
//
// Morphing targets (ControlTarget::swaps): a swap inside a frame ends the frame's submission at that sub-step
// (prepare_frame says where); the next starts with the new sample set, its buffers made again and the passes bound to
// them, as the CPU controller takes the new set at the same sub-step.
//
// Kinematic corrections (AdaptiveParams::kinematic): the spring's and the density constraint's Δx also go into the
// fluid's shift (PbfDevice::shift_buffer), which the sub-step's update takes out of the velocity, as the CPU's.
#include "control/adaptive_params.h"
#include "control/control_context.h"
#include "control/control_samples.h"
#include "control/control_targets.h"
#include "core/error.h"
#include "gpu/kernel.h"
#include "gpu/pbf_device.h"
#include "pose/target_motion.h"

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

namespace ff::gpu {

class AdaptiveDevice final : public DeviceController {
 public:
  /// The controller of `targets` for the fluid of `fluid` (which must outlive it).
  static Result<std::unique_ptr<AdaptiveDevice>> create(PbfDevice& fluid, std::vector<control::ControlTarget> targets,
                                                        const control::ControlContext& ctx,
                                                        const control::AdaptiveParams& params);
  /// Each fluid particle's target (sim::ParticleSet::target), in the fluid's order.
  Status set_fluid_targets(std::span<const std::uint8_t> target);
  /// Per fluid particle, its nearest bonded sample as an index into the targets' concatenated sets
  /// (sim::ParticleSet::bound_control), kInvalidIndex when not controlled: of the last sub-step.
  Status get_bound(std::vector<Index>& bound) const;
  /// Per sample (in the targets' concatenated order), its fill ratio ρ_p/ρ_c at the start of the last sub-step.
  Status get_fill(std::vector<float>& fill) const;
  std::size_t samples() const { return m_; }
  /// The gather steering's field of the last sub-step (with AdaptiveParams::gather): per target and cell of
  /// `field()`, its seed as an index into the targets' concatenated sets, or kInvalidIndex.
  Status get_seeds(std::vector<Index>& seeds) const;
  const GridSpec& field() const { return field_; }
  /// Live steering (control/steering.h): target `t` holds `pose` from the next frame on; a static target starts
  /// moving (its poses are uploaded every frame from then on). An index past the last target is ignored.
  Status set_target_pose(std::size_t t, const pose::Pose& pose);

  Result<int> prepare_frame(double time, float dt, int from, int substeps) override;
  void record_begin(VkCommandBuffer cb, float dt, int substep) const override;
  void record_accelerations(VkCommandBuffer cb, float dt) const override;
  void record_correction(VkCommandBuffer cb, int iteration, float dt) const override;

  struct Constants;  ///< the control passes' push-constant block (adaptive_device.cpp)

 private:
  AdaptiveDevice() = default;
  Constants constants(float dt) const;
  Constants accel_constants(float dt) const;
  Status prepare_strengths(double time, float dt, std::size_t steps);
  Status make_buffers();
  Status make_sample_buffers();
  Status make_kernels();
  Status take_swap();
  Status upload_moving();

  PbfDevice* fluid_ = nullptr;
  // Posed on the host, as the CPU controller poses its own; while moving() (keyframes, a skin, a live pose), every
  // frame's poses are uploaded.
  control::ControlSamples samples_;
  DeviceBuffer s_vel_, t_moving_;    // u_c per sample (0 when static); per target 1 when it moves
  bool timed_ = false;               // some target starts late or has a strength track: strengths every sub-step
  bool morphs_ = false;              // some target swaps its sample set (a morph): frames may end a submission early
  bool swap_pending_ = false;        // samples_ took a new set whose buffers and passes are not all made yet
  DeviceBuffer t_strength_;          // per target, its strength in this sub-step (1 throughout when not timed_)
  DeviceBuffer step_strength_;       // the frame's sub-steps' strengths, targets after targets
  // Per target (x, y): the factor of max_speed and gather_speed, and of the clamp (at most one spacing), from
  // control::speed_scales.
  DeviceBuffer t_speed_;
  std::size_t strength_steps_ = 0;   // sub-steps step_strength_ has room for
  DeviceBuffer pose_pos_, pose_vel_, pose_nrm_;  // the frame's sub-steps' poses, one after the other
  std::size_t pose_steps_ = 0;       // sub-steps pose_pos_ has room for
  control::AdaptiveParams params_;
  control::ControlContext ctx_;
  std::size_t m_ = 0;
  float hc_ = 0, eps_c_ = 0, g_ref_ = 0;
  bool multi_ = false;
  std::vector<Index> original_;  // sample k on the device is original_[k] in the concatenated sets
  DeviceBuffer s_pos_, s_normal_, s_rho_c_, s_phi_, s_target_;
  PbfDevice::PointGrid s_grid_;  // the samples in the fluid grid's cells
  DeviceBuffer s_fill_, s_bond_r2_, s_coef_, f_target_, nearest_;
  Kernel fill_k_, bonds_k_, accel_k_, spring_k_, lambda_k_, correct_k_;
  // The gather steering's seed field: the CPU field's cells (control/nearest_seed_field.h), one field per target.
  GridSpec field_;
  std::size_t targets_ = 1;
  std::vector<int> jumps_;         // the flood passes
  PbfDevice::PointGrid s_field_;   // the samples in the field's cells
  DeviceBuffer seed_a_, seed_b_;   // targets × cells; the result ends in seed_a_
  Kernel seed_init_k_, flood_ab_k_, flood_ba_k_, gather_k_;
  Constants gather_constants(float dt, int jump) const;
  Status make_seed_field(std::size_t targets);
  void record_seed_field(VkCommandBuffer cb, float dt) const;
};

}  // namespace ff::gpu
