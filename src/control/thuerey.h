#pragma once
// `thuerey`: Thürey, Keiser, Pauly, Rüde, "Detail-Preserving Fluid Control", SCA 2006 (METHOD.md §b.0), as the
// authors' El'Beem code behaves, in our SPH units. Hook (i) only: accelerations.
//   fill of control particle j   ρ̃_j = Σ_p w_a(|x_p − c_j|) / N_full,  q_j = clamp(1 − ρ̃_j, 0, 1)
//   attraction on fluid p        A_p = Σ_j q_j (c_j − x_p)/|c_j − x_p|,  Ω_p = Σ_j q_j w_a, scaled by Ω_p (≤ 1) or
//                                1/Ω_p (> 1), a = α A_p
//   velocity control             Δv_p = β_Δt Ω_v (ū_p − ṽ_p) on the low-pass velocity ṽ_p (the paper's detail
//                                preservation), ū_p the w_v-weighted control velocity, β_Δt = 1 − (1 − β)^{Δt/0.01}
// Controlled: within R_a of a control particle (every such particle also receives Δv).
#include "control/controller_info.h"
#include "control/baseline_core.h"
#include "control/steering.h"
#include "sim/controller.h"

#include <memory>

namespace ff::control {

struct ThuereyParams {
  static constexpr ControllerInfo info{"thuerey", "Thuerey et al. 2006: attraction by fill level + detail-preserving velocity control", false};
  float attraction = 20.0f;  ///< α, m/s² (METHOD §b.0 [D]; El'Beem 0.2 in LBM units). [0, 1000]
  float velocity = 0.2f;     ///< β, velocity-control strength per 0.01 s. [0, 1]
  float radius = 1.0f;       ///< R_a = R_v = radius · H_c. [0.25, 2]
  float fill_radius = 0.75f; ///< N_full counts the particles of a ball of fill_radius · R_a (El'Beem). [0.1, 2]

  template <class S, class F>
  static void fields(S& s, F&& f) {
    f("attraction", s.attraction, core::closed(0.0, 1000.0, "α, m/s² (METHOD §b.0 [D]; El'Beem 0.2 in LBM units)"));
    f("velocity", s.velocity, core::closed(0.0, 1.0, "β, velocity-control strength per 0.01 s"));
    f("radius", s.radius, core::closed(0.25, 2.0, "R_a = R_v = radius · H_c"));
    f("fill_radius", s.fill_radius, core::closed(0.1, 2.0, "N_full counts the particles of a ball of fill_radius · R_a (El'Beem)"));
  }
  Status validate(std::string_view path = "controller.thuerey") const { return core::validate_fields(*this, path); }
};

class ThuereyController final : public sim::Controller, public Steerable {
 public:
  /// Live steering (control/steering.h): the shared core moves the samples.
  void set_target_pose(std::size_t t, const pose::Pose& pose) override { harness_.set_target_pose(t, pose); }
  static Result<std::unique_ptr<ThuereyController>> create(std::vector<ControlTarget> targets, const ControlContext& ctx,
                                                           const ThuereyParams& params);
  std::string_view name() const override { return "thuerey"; }
  void begin_step(const sim::StepView& view, sim::ParticleSet& p) override;
  void add_accelerations(const sim::StepView& view, sim::ParticleSet& p) override;

 private:
  explicit ThuereyController(const ThuereyParams& params) : params_(params) {}
  ThuereyParams params_;
  BaselineCore harness_;
  float ra_ = 0.0f, n_full_ = 1.0f;
  std::vector<float> q_;  // 1 − fill, per control particle
};

/// The controller table's factory (control/registry.h).
inline Result<std::unique_ptr<sim::Controller>> make_controller(std::vector<ControlTarget> targets, const ControlContext& ctx,
                                                               const ThuereyParams& params) {
  return as_controller(ThuereyController::create(std::move(targets), ctx, params));
}

}  // namespace ff::control
