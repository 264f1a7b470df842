#pragma once
// `rscf` [A]: Lu et al., "A Rigging-Skinning Scheme to Control Fluid Simulation", PG 2019 (METHOD.md §b.2). Its
// skinning equations are not public; this is the documented approximation. The rig is the control samples; the
// "skin" carries the rig's zero-order (Shepard-interpolated position x̄_p and velocity ū_p) and first-order
// (velocity gradient G_p) features to every fluid particle within H_c, as an acceleration:
//   a = k_x (x̄_p − x_p)/Δt_ref² + k_v (ū_p + G_p (x_p − x̄_p) − v_p)/Δt_ref,  Δt_ref = 1/60 s
// No density term: fluid is pulled toward rig points whatever the local fill. Controlled: within H_c of the rig.
#include "control/controller_info.h"
#include "control/baseline_core.h"
#include "control/steering.h"
#include "sim/controller.h"

#include <memory>

namespace ff::control {

struct RscfParams {
  static constexpr ControllerInfo info{"rscf", "Lu et al. 2019 (rigging-skinning): Shepard-skinned rig position and velocity, no density term", true};
  float position = 0.02f;  ///< k_x, zero-order position feature. [0, 1]
  float velocity = 0.2f;   ///< k_v, zero-order velocity feature. [0, 1]
  float gradient = 1.0f;   ///< weight of the first-order (velocity-gradient) feature; 0 switches it off. [0, 1]

  template <class S, class F>
  static void fields(S& s, F&& f) {
    f("position", s.position, core::closed(0.0, 1.0, "k_x, zero-order position feature"));
    f("velocity", s.velocity, core::closed(0.0, 1.0, "k_v, zero-order velocity feature"));
    f("gradient", s.gradient, core::closed(0.0, 1.0, "weight of the first-order (velocity-gradient) feature; 0 switches it off"));
  }
  Status validate(std::string_view path = "controller.rscf") const { return core::validate_fields(*this, path); }
};

class RscfController final : public sim::Controller, public Steerable {
 public:
  /// Live steering (control/steering.h): the shared core moves the samples.
  void set_target_pose(std::size_t t, const pose::Pose& pose) override { harness_.set_target_pose(t, pose); }
  static Result<std::unique_ptr<RscfController>> create(std::vector<ControlTarget> targets, const ControlContext& ctx,
                                                        const RscfParams& params);
  std::string_view name() const override { return "rscf"; }
  void begin_step(const sim::StepView& view, sim::ParticleSet& p) override;
  void add_accelerations(const sim::StepView& view, sim::ParticleSet& p) override;

 private:
  explicit RscfController(const RscfParams& params) : params_(params) {}
  RscfParams params_;
  BaselineCore harness_;
};

/// The controller table's factory (control/registry.h).
inline Result<std::unique_ptr<sim::Controller>> make_controller(std::vector<ControlTarget> targets, const ControlContext& ctx,
                                                               const RscfParams& params) {
  return as_controller(RscfController::create(std::move(targets), ctx, params));
}

}  // namespace ff::control
