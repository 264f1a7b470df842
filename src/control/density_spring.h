#pragma once
// The engine `pbfc` and `weighted` share (METHOD.md §b.1, §b.4): three position constraints, solved once per
// sub-step after prediction, before the PBF iterations (iteration 0 of correct_positions):
//   1. a bilateral density constraint per control particle i, C_i = ρ_i/ρ_0,i − 1 on the fluid at x*:
//      λ_i = −C_i / (Σ_p |g_ip|² + ε_c), g_ip = (m_p/ρ_0,i) ∇W_spiky(x_ci − x*_p, H_c),
//      Δx_p = −α Σ_i w_i λ_i g_ip (attracts while under-dense, repels while over-dense)
//   2. the adaptive spring: each fluid particle keeps a reference control particle r(p), its nearest one,
//      refreshed every sub-step while within D/2 (lifetime reset to T); it survives T sub-steps after leaving.
//      While alive: Δx_p += β d σ(ℓ) (x_r − x*_p)/ℓ, σ(ℓ) = 1/(1 + exp(a (b − ℓ))): ~0 near the control
//      particle, ~1 once the particle has drifted beyond b, so it acts only on escaping particles
//   3. a velocity constraint: Δx_p += γ Δt (ū_p − v_p), ū_p the Poly6-weighted control velocity around p
// `pbfc` uses one rest density ρ_0 (a full fluid neighbourhood's) and w_i = 1; `weighted` asks each control
// particle for its own ρ_c,i and weights it from the colour field of the samples (and has no velocity term).
// Controlled: within H_c of a control particle of its target, or a live spring.
#include "control/baseline_core.h"
#include "control/steering.h"
#include "sim/controller.h"

#include <cmath>
#include <memory>
#include <string>

namespace ff::control {

struct DensitySpringConfig {
  std::string name;
  float alpha = 1.0f;         ///< density-constraint strength
  float epsilon = 1.0f;       ///< ε_c as a multiple of S_0 (control_targets.h)
  float spring = 0.5f;        ///< β, spring step in spacings d per sub-step
  float spring_start = 1.5f;  ///< b, in H_c
  float steepness = 10.0f;    ///< a · H_c
  float bond_reach = 1.0f;    ///< D, in H_c: the reference is refreshed while within D/2
  int lifetime = 3;           ///< T, sub-steps
  float velocity = 0.2f;      ///< γ (static target)
  float velocity_moving = 1.0f;  ///< γ while the target moves
  bool per_sample_density = false;  ///< ρ_0,i = ρ_c,i (weighted) instead of one ρ_0 (pbfc)
  float kappa = 0.0f;         ///< colour-field weight w_i = 1 + κ (1 − cf_i/max cf); 0 → w_i = 1
};

/// The fields pbfc's and weighted's parameter structs share, copied into a config that each then completes.
template <class P>
DensitySpringConfig density_spring_config(const P& params, std::string name) {
  DensitySpringConfig cfg;
  cfg.name = std::move(name);
  cfg.alpha = params.alpha, cfg.epsilon = params.epsilon;
  cfg.spring = params.spring, cfg.spring_start = params.spring_start, cfg.steepness = params.steepness;
  cfg.bond_reach = params.bond_reach, cfg.lifetime = static_cast<int>(std::lround(params.lifetime));
  return cfg;
}

class DensitySpringController final : public sim::Controller, public Steerable {
 public:
  /// Live steering (control/steering.h): the shared core moves the samples.
  void set_target_pose(std::size_t t, const pose::Pose& pose) override { harness_.set_target_pose(t, pose); }
  static Result<std::unique_ptr<DensitySpringController>> create(std::vector<ControlTarget> targets,
                                                                 const ControlContext& ctx, DensitySpringConfig cfg);
  std::string_view name() const override { return cfg_.name; }
  void begin_step(const sim::StepView& view, sim::ParticleSet& p) override;
  void correct_positions(const sim::StepView& view, sim::ParticleSet& p) override;

 private:
  explicit DensitySpringController(DensitySpringConfig cfg) : cfg_(std::move(cfg)) {}
  void sample_weights();
  DensitySpringConfig cfg_;
  BaselineCore harness_;
  float rho0_ = 0.0f, eps_c_ = 0.0f;
  bool moving_ = false;
  std::vector<float> w_, lambda_;     // per control particle
  std::vector<Index> ref_;            // per fluid particle id: reference control particle (kInvalidIndex: none)
  std::vector<std::int32_t> life_;    // per fluid particle id: sub-steps the spring has left
};

}  // namespace ff::control
