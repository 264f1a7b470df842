#pragma once
// `pbfc`: Zhang, Yang, Wu, Liu, "Position-based Fluid Control", i3D 2015 (METHOD.md §b.1): a bilateral density
// constraint per control particle with one rest density, the adaptive spring on escaping particles and the
// velocity constraint, on the engine in density_spring.h. Scale-free defaults of METHOD §b.1 [D], chosen once.
#include "control/controller_info.h"
#include "control/density_spring.h"

namespace ff::control {

struct PbfcParams : SpringBondParams {  // spring, spring_start, steepness, bond_reach, lifetime: the adaptive spring
  static constexpr ControllerInfo info{"pbfc", "Zhang et al. 2015 (PBFC): bilateral density constraint, adaptive spring, velocity constraint", false};
  float alpha = 1.0f;            ///< α, density-constraint strength. [0, 10]
  /// ε_c as a multiple of S_0. [0.01, 100] Chosen once on the bunny (~3k samples, 150 frames, the harness's CFL
  /// sub-steps): ε = 1, 10, 100 gave E 1.13, 1.05, 1.50 %; at 1 an empty target pulls the first fluid in at
  /// ~15 m/s and the CFL rule takes up to 64 sub-steps a frame.
  float epsilon = 10.0f;
  float velocity = 0.2f;         ///< γ of the velocity constraint. [0, 1]
  float velocity_moving = 1.0f;  ///< γ while the target moves. [0, 1]

  template <class S, class F>
  static void fields(S& s, F&& f) {
    f("alpha", s.alpha, core::closed(0.0, 10.0, "α, density-constraint strength"));
    f("epsilon", s.epsilon, core::closed(0.01, 100.0, "ε_c as a multiple of S_0"));
    SpringBondParams::fields(s, f, SpringBondParams::kPbfcDocs);
    f("velocity", s.velocity, core::closed(0.0, 1.0, "γ of the velocity constraint"));
    f("velocity_moving", s.velocity_moving, core::closed(0.0, 1.0, "γ while the target moves"));
  }
  Status validate(std::string_view path = "controller.pbfc") const { return core::validate_fields(*this, path); }
};

Result<std::unique_ptr<sim::Controller>> make_controller(std::vector<ControlTarget> targets, const ControlContext& ctx,
                                                   const PbfcParams& params);

}  // namespace ff::control
