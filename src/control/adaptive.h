#pragma once
// `adaptive`: the paper's controller (Zhou et al., §4, Algorithms 1–2), as specified in METHOD.md §a.2–§a.6.
//
// Per sub-step (the solver's hook order, METHOD §a.6):
//   begin_step        sample → fluid pairs within H_c (one grid query; samples are kept sorted by cell, so
//                     neighbouring queries share candidates); ρ_p,i at x; bond radius H_c*,i (eq. 19);
//                     bonds B(j) = {i : |x_ci − x_j| ≤ H_c*,i} (frozen for the sub-step), the transpose of the
//                     pairs by a counting sort; controlled = B(j) ≠ ∅
//   add_accelerations boundary correction (eq. 15–16) for controlled particles; gather (ours, §a.10) for
//                     unbonded particles of a target that is not full
//   correct_positions iteration 0: the adaptive spring (eq. 17–18, once per sub-step);
//                     every iteration: λ_i of the unilateral density constraint C_i = min(ρ_p,i/ρ_c,i − 1, 0)
//                     at x* (eq. 6–8), then Δx_j = α Σ_{i∈B(j)} φ̃_i λ_i g_ij (eq. 10), clamped
// Fluid particle j belongs to one target (ParticleSet::target) and only that target's samples act on it:
// "each model independently controls the fluid", and no particle can be pulled back and forth between
// targets. Every loop is a gather with a fixed order (the transpose keeps each particle's bonds in ascending
// sample order), so a run is bit-identical for any thread count.
#include "control/adaptive_params.h"
#include "control/control_context.h"
#include "control/control_samples.h"
#include "control/control_targets.h"
#include "control/nearest_seed_field.h"
#include "control/steering.h"
#include "pose/target_motion.h"
#include "core/kernels.h"
#include "core/neighbor_grid.h"
#include "sampling/control_set.h"
#include "sim/controller.h"

#include <vector>

namespace ff::control {

/// A sample's position and one per-pass value, 16-byte aligned for one load (see AdaptiveController::sample_xw_).
struct alignas(16) PackedSample {
  float x, y, z, w;
};

class AdaptiveController final : public sim::Controller, public Steerable {
 public:
  /// Every target's set must have the same support H_c (they are sampled at one spacing).
  static Result<std::unique_ptr<AdaptiveController>> create(std::vector<ControlTarget> targets, const ControlContext& ctx,
                                                            const AdaptiveParams& params);

  std::string_view name() const override { return "adaptive"; }
  /// Live steering (control/steering.h): the samples follow `pose` from the next sub-step on.
  void set_target_pose(std::size_t target, const pose::Pose& pose) override;
  void begin_step(const sim::StepView& view, sim::ParticleSet& p) override;
  void add_accelerations(const sim::StepView& view, sim::ParticleSet& p) override;
  void correct_positions(const sim::StepView& view, sim::ParticleSet& p) override;

 private:
  AdaptiveController(const ControlContext& ctx, const AdaptiveParams& params, float hc);
  // Whether target t acts in this sub-step (started, strength above 0); strength_[t] is its strength then.
  bool active(std::uint8_t t, double time) const { return samples_.acting(t, time); }
  void adaptive_spring(sim::ParticleSet& p, float dt) const;
  void control_correction(sim::ParticleSet& p, float dt);
  // The scale α and the clamp of a control displacement Δx_j (METHOD §a.3), applied to x*_j (and the shift).
  struct CorrectionLimit {
    float alpha;
    const float* max_dx;  // per target
    std::size_t targets;  // max_dx's length: a particle of no target (only with one target) takes target 0's
    bool kinematic;
    void apply(sim::ParticleSet& p, std::size_t j, Vec3f dx) const;
  };
  void sample_lambdas(sim::ParticleSet& p);
  void print_active_set() const;
  void scatter_correction(sim::ParticleSet& p, const CorrectionLimit& limit);
  void gather_correction(sim::ParticleSet& p, const CorrectionLimit& limit);
  void gather(sim::ParticleSet& p);
  // begin_step, step 1: each target's strength at this sub-step, whether any is softened, whether each moves.
  void update_strengths();
  // begin_step, step 2: each sample's density ρ_p,i at x, fill ratio and bond radius H_c*,i (eq. 8, 19) and its
  // bond masks, in T sample ranges whose bonds per fluid particle are counted into cursor_ (for build_bonds).
  void fill_samples(const sim::ParticleSet& p);
  void build_bonds(sim::ParticleSet& p);
  // Calls f(j) for each fluid particle j bonded to sample i (its pairs in cf_, one bit each in bond_mask_).
  template <class F>
  void for_each_bond(std::size_t i, F&& f) const;

  ControlContext ctx_;
  AdaptiveParams params_;
  float hc_ = 0, d_ = 0;
  core::Poly6 poly6_;
  core::Spiky spiky_;
  float eps_c_ = 0;   // ε_c = epsilon · S_0
  // Every target's samples at their pose, in cell order, with their normals and g_ref (eq. 15–16).
  ControlSamples samples_;
  // Per sub-step.
  double time_ = 0.0;
  std::vector<float> strength_;     // per target: its control strength in this sub-step (control/strength.h)
  bool softened_ = false;           // some target acts with a strength below 1
  std::vector<std::uint8_t> target_moving_;  // per target: it moves (follow applies to its fluid)
  // Per target, the factor its speeds run at (AdaptiveParams::speed_reference), from its current sample set.
  std::vector<float> speed_scale_;
  std::vector<float> max_dx_;       // per target, the clamp of this sub-step's corrections
  float speed_of(std::uint8_t t) const { return t < speed_scale_.size() ? speed_scale_[t] : 1.0f; }
  core::NeighborGrid fluid_grid_;
  core::NeighborList cf_;           // sample i → fluid within H_c
  std::vector<float> fill_, bond_radius2_, lambda_;  // ρ_p/ρ_c at the start of the sub-step; bond radius H_c*²; λ
  // CSR: fluid j → bonded samples (ascending), each list padded to a multiple of four with the sentinel sample
  // m (far away, coefficient 0), so the bond loops load whole groups without tests; empty lists stay empty.
  std::vector<Index> bond_off_, bond_idx_;
  std::vector<Index> bond_end_;             // fluid j → end of its real bonds (before the padding)
  // Per sample (and the sentinel at m): x, y, z and a per-pass value w (the fill ratio for the spring, then the
  // control coefficient φ̃ λ m_p/ρ_c kg in each iteration), so a bond loop fetches a sample in one 16-byte load.
  std::vector<PackedSample> sample_xw_;
  std::vector<Index> nearest_;              // fluid j → its nearest bonded sample (kInvalidIndex: none)
  std::vector<Index> cursor_;               // per thread × fluid: bond counts, then write cursors
  std::vector<Index> mask_group_start_;     // per sample: first group of four pairs in bond_mask_
  std::vector<std::uint8_t> bond_mask_;     // per group of four sample → fluid pairs: which are bonds
  std::vector<Index> seeds_, active_;  // active_: samples with λ > 0 in the current iteration
  std::vector<Vec3f> dx_;                // scattered control corrections (few active samples)
  std::vector<std::uint8_t> touched_;
  std::vector<NearestSeedField> seed_field_;  // per target
};

/// The controller table's factory (control/registry.h).
inline Result<std::unique_ptr<sim::Controller>> make_controller(std::vector<ControlTarget> targets, const ControlContext& ctx,
                                                               const AdaptiveParams& params) {
  return as_controller(AdaptiveController::create(std::move(targets), ctx, params));
}

}  // namespace ff::control
