#pragma once
// What every controller is told about the fluid it controls (METHOD.md §0). Plain data from the solver.
#include "core/types.h"
#include "sim/solver_params.h"

namespace ff::control {

struct ControlContext {
  float particle_radius = 0.025f;  ///< r, m (spacing d = 2r)
  float particle_mass = 0.0f;      ///< m_p = ρ_phys d³, kg
  float rest_density = 1000.0f;    ///< physical ρ0, kg/m³ (the control densities are calibrated to it)
  Vec3f gravity{0.0f, -10.0f, 0.0f};
  sim::Domain domain;
  float fluid_support = 0.0f;      ///< H_p, m (0: the default 2 d)
  float spacing() const { return 2.0f * particle_radius; }
  float support() const { return fluid_support > 0.0f ? fluid_support : 2.0f * spacing(); }
};

}  // namespace ff::control
