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
#include "core/fields.h"
#include "sim/controller.h"

#include <cmath>
#include <memory>
#include <string>

namespace ff::control {

/// The adaptive spring's parameters (step 2 above: its step, its logistic switch, the reach of its bond to a reference
/// control particle and the bond's lifetime), which `pbfc` and `weighted` both take: their parameter structs derive
/// from it and list its fields among their own, under the same keys (controller.pbfc.spring,
/// controller.weighted.spring, ...).
struct SpringBondParams {
  float spring = 0.5f;        ///< β, spring step in spacings d per sub-step. [0, 5]
  float spring_start = 1.5f;  ///< b, where the logistic switch is half on, in H_c. [0, 10]
  float steepness = 10.0f;    ///< a · H_c, the switch's steepness. [0.1, 1000]
  float bond_reach = 1.0f;    ///< D in H_c: the reference is refreshed while within D/2. [0.1, 4]
  float lifetime = 3.0f;      ///< T, sub-steps a spring survives after its particle left D/2. [0, 1000]

  /// The fields' meanings in the key table: pbfc's, and weighted's (which point to pbfc's).
  struct Docs {
    std::string_view spring, spring_start, steepness, bond_reach, lifetime;
  };
  static constexpr Docs kPbfcDocs{"β, spring step in spacings d per sub-step",
                                  "b, where the logistic switch is half on, in H_c", "a · H_c, the switch's steepness",
                                  "D in H_c: the reference is refreshed while within D/2",
                                  "T, sub-steps a spring survives after its particle left D/2"};
  static constexpr Docs kAsPbfcDocs{"as pbfc", "as pbfc, in H_c", "as pbfc", "as pbfc, in H_c", "as pbfc, sub-steps"};

  template <class S, class F>
  static void fields(S& s, F&& f, const Docs& docs = kPbfcDocs) {
    f("spring", s.spring, core::closed(0.0, 5.0, docs.spring));
    f("spring_start", s.spring_start, core::closed(0.0, 10.0, docs.spring_start));
    f("steepness", s.steepness, core::closed(0.1, 1000.0, docs.steepness));
    f("bond_reach", s.bond_reach, core::closed(0.1, 4.0, docs.bond_reach));
    f("lifetime", s.lifetime, core::closed(0.0, 1000.0, docs.lifetime));
  }
};

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

/// The fields pbfc's and weighted's parameter structs share (α, ε_c and their SpringBondParams), copied into a config
/// that each then completes.
template <class P>
DensitySpringConfig density_spring_config(const P& params, std::string name) {
  const SpringBondParams& sb = params;
  DensitySpringConfig cfg;
  cfg.name = std::move(name);
  cfg.alpha = params.alpha, cfg.epsilon = params.epsilon;
  cfg.spring = sb.spring, cfg.spring_start = sb.spring_start, cfg.steepness = sb.steepness;
  cfg.bond_reach = sb.bond_reach, cfg.lifetime = static_cast<int>(std::lround(sb.lifetime));
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
