#pragma once
// `weighted` [A]: Zhou et al.'s earlier target-driven control (METHOD.md §b.4; its equations are not public, this
// is the documented approximation): control-particle weights from the samples' SPH colour field, a bilateral
// density constraint toward each control particle's own density ρ_c,i (sparse regions ask for less fluid) and the
// adaptive spring of `pbfc`; no bond breaking, no boundary correction, no velocity term.
#include "control/controller_info.h"
#include "control/density_spring.h"

namespace ff::control {

struct WeightedParams : SpringBondParams {  // spring, spring_start, steepness, bond_reach, lifetime: as pbfc
  static constexpr ControllerInfo info{"weighted", "Zhou et al. (ref. [60]): colour-field weights, bilateral density to rho_c, adaptive spring", true};
  float alpha = 1.0f;         ///< density-constraint strength. [0, 10]
  /// ε_c as a multiple of S_0. [0.01, 100] Chosen once on the bunny as pbfc's: ε = 1, 10, 100 gave E 0.72, 1.04,
  /// 4.81 %.
  float epsilon = 1.0f;
  float kappa = 1.0f;         ///< κ of the colour-field weight w_i = 1 + κ (1 − cf_i/max cf). [0, 10]

  template <class S, class F>
  static void fields(S& s, F&& f) {
    f("alpha", s.alpha, core::closed(0.0, 10.0, "density-constraint strength"));
    f("epsilon", s.epsilon, core::closed(0.01, 100.0, "ε_c as a multiple of S_0. [0.01, 100] Chosen once on the bunny as pbfc's: ε = 1, 10, 100 gave E 0.72, 1.04,"));
    f("kappa", s.kappa, core::closed(0.0, 10.0, "κ of the colour-field weight w_i = 1 + κ (1 − cf_i/max cf)"));
    SpringBondParams::fields(s, f, SpringBondParams::kAsPbfcDocs);
  }
  Status validate(std::string_view path = "controller.weighted") const { return core::validate_fields(*this, path); }
};

Result<std::unique_ptr<sim::Controller>> make_controller(std::vector<ControlTarget> targets, const ControlContext& ctx,
                                                       const WeightedParams& params);

}  // namespace ff::control
