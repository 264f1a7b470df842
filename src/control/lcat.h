#pragma once
// `lcat` [A]: Schoentgen, Poulin, Darles, Meseure, "Particle-based Liquid Control using Animation Templates",
// SCA 2020 (METHOD.md §b.3). Its force formulas are not public; this is the documented approximation. A static
// target is a template of the control samples at rest (u_T = 0, template density ρ_T = ρ_c):
//   density force   a = k_ρ Σ_t δ_t W(r_pt) (x_t − x_p)/r_pt / max(1, Σ_t W/W(0)),  δ_t = max(0, 1 − ρ_f(x_t)/ρ_T,t)
//   velocity force  a += k_v (ū_T(x_p) − v_p)/Δt_ref
//   temporaries     every sub-step, a template particle with ρ_f/ρ_T < 0.5 and no fluid within d/2 spawns a fluid
//                   particle at x_t with velocity u_t, until the temporaries number τ · N_T (they live as long as
//                   the template, here the whole run; the run's report counts them as added particles)
// Repulsion particles are off (METHOD §b.3 default). Controlled: within H_c of a template particle, and every
// temporary.
#include "control/controller_info.h"
#include "control/baseline_core.h"
#include "control/steering.h"
#include "sim/controller.h"

#include <memory>

namespace ff::control {

struct LcatParams {
  static constexpr ControllerInfo info{"lcat", "Schoentgen et al. 2020 (animation templates): template density and velocity forces, temporary particles", true};
  float density = 20.0f;      ///< k_ρ, m/s². [0, 1000]
  float velocity = 0.2f;      ///< k_v. [0, 1]
  float temporaries = 0.3f;   ///< τ, temporaries allowed as a fraction of the template particles. [0, 1]
  float spawn_fill = 0.5f;    ///< a template particle spawns while ρ_f/ρ_T is below this. [0, 1]

  template <class S, class F>
  static void fields(S& s, F&& f) {
    f("density", s.density, core::closed(0.0, 1000.0, "k_ρ, m/s²"));
    f("velocity", s.velocity, core::closed(0.0, 1.0, "k_v"));
    f("temporaries", s.temporaries, core::closed(0.0, 1.0, "τ, temporaries allowed as a fraction of the template particles"));
    f("spawn_fill", s.spawn_fill, core::closed(0.0, 1.0, "a template particle spawns while ρ_f/ρ_T is below this"));
  }
  Status validate(std::string_view path = "controller.lcat") const { return core::validate_fields(*this, path); }
};

class LcatController final : public sim::Controller, public Steerable {
 public:
  /// Live steering (control/steering.h): the shared core moves the samples.
  void set_target_pose(std::size_t t, const pose::Pose& pose) override { harness_.set_target_pose(t, pose); }
  static Result<std::unique_ptr<LcatController>> create(std::vector<ControlTarget> targets, const ControlContext& ctx,
                                                        const LcatParams& params);
  std::string_view name() const override { return "lcat"; }
  void begin_step(const sim::StepView& view, sim::ParticleSet& p) override;
  void add_accelerations(const sim::StepView& view, sim::ParticleSet& p) override;
  void emit(const sim::StepView& view, sim::ParticleSet& p) override;
  std::size_t temporaries() const { return spawned_; }

 private:
  explicit LcatController(const LcatParams& params) : params_(params) {}
  LcatParams params_;
  BaselineCore harness_;
  std::vector<float> delta_;            // δ_t per template particle
  std::vector<std::uint8_t> wants_;     // template particle may spawn (under-filled, no fluid within d/2)
  std::size_t spawned_ = 0;
  std::vector<std::uint8_t> temporary_; // per particle id: a temporary
};

/// The controller table's factory (control/registry.h).
inline Result<std::unique_ptr<sim::Controller>> make_controller(std::vector<ControlTarget> targets, const ControlContext& ctx,
                                                               const LcatParams& params) {
  return as_controller(LcatController::create(std::move(targets), ctx, params));
}

}  // namespace ff::control
