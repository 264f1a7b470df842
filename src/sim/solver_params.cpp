#include "sim/solver_params.h"

#include "core/params.h"

#include <fmt/format.h>

namespace ff::sim {
using core::Bound;
using core::check_range;

Status SolverParams::validate(std::string_view p) const {
  FF_CHECK(check_range(p, "particle_radius", particle_radius, 1e-4, 10.0, Bound::Open));
  FF_CHECK(check_range(p, "support_factor", support_factor, 2.5, 8.0));
  FF_CHECK(check_range(p, "iterations", iterations, 1, 100));
  FF_CHECK(check_range(p, "max_iterations", max_iterations, iterations, 1000));
  FF_CHECK(check_range(p, "max_density_error", max_density_error, 0.0, 1.0, Bound::Open));
  FF_CHECK(check_range(p, "max_dt", max_dt, 0.0, 0.1, Bound::Open));
  FF_CHECK(check_range(p, "cfl", cfl, 0.0, 1.0, Bound::Open));
  FF_CHECK(check_range(p, "max_substeps", max_substeps, 1, 10000));
  FF_CHECK(core::check_vec(p, "gravity", gravity, -1000.0, 1000.0));
  FF_CHECK(check_range(p, "rest_density", rest_density, 0.0, 1e5, Bound::Open));
  FF_CHECK(check_range(p, "viscosity", viscosity, 0.0, 1.0));
  FF_CHECK(check_range(p, "vorticity", vorticity, 0.0, 10.0));
  FF_CHECK(check_range(p, "epsilon", epsilon, 0.0, 100.0, Bound::Open));
  FF_CHECK(check_range(p, "scorr_k", scorr_k, 0.0, 1.0));
  FF_CHECK(check_range(p, "scorr_n", scorr_n, 1, 8));
  FF_CHECK(check_range(p, "scorr_dq", scorr_dq, 0.0, 1.0, Bound::Open, Bound::Open));
  FF_CHECK(check_range(p, "surface_tension", surface_tension, 0.0, 10.0));
  FF_CHECK(check_range(p, "surface_tension_samples", surface_tension_samples, 1.0, 1e6));
  FF_CHECK(check_range(p, "drag", drag, 0.0, 10.0));
  FF_CHECK(check_range(p, "air_density", air_density, 0.0, 100.0, Bound::Open));
  return {};
}

Status Domain::validate(float r, std::string_view p) const {
  FF_CHECK(core::check_vec(p, "min", min, -1e6, 1e6));
  FF_CHECK(core::check_vec(p, "max", max, -1e6, 1e6));
  for (int a = 0; a < 3; ++a)
    if (!(max[a] - min[a] >= 4.0f * r))
      return param_error(fmt::format("{}: max[{}] − min[{}] = {} must be at least 4 particle radii ({})", p, a, a,
                                     max[a] - min[a], 4.0f * r));
  return {};
}

Status FluidSource::validate(std::string_view p) const {
  FF_CHECK(core::check_vec(p, "velocity", velocity, -1e4, 1e4));
  if (shape == Shape::Box) {
    FF_CHECK(core::check_vec(p, "min", min, -1e6, 1e6));
    FF_CHECK(core::check_vec(p, "max", max, -1e6, 1e6));
    for (int a = 0; a < 3; ++a)
      if (!(max[a] > min[a]))
        return param_error(fmt::format("{}: box max[{}] = {} must be greater than min[{}] = {}", p, a, max[a], a, min[a]));
  } else {
    FF_CHECK(core::check_vec(p, "center", center, -1e6, 1e6));
    FF_CHECK(check_range(p, "radius", radius, 0.0, 1e6, Bound::Open));
  }
  return {};
}

}  // namespace ff::sim
