#include "sim/solver_params.h"

#include "core/params.h"

#include <cmath>
#include <limits>
#include <numbers>

#include <fmt/format.h>

namespace ff::sim {
using core::Bound;
using core::check_range;

double SolverParams::capillary_dt() const {
  if (!(surface_tension > 0.0f) || !(capillary_cfl > 0.0f)) return std::numeric_limits<double>::infinity();
  const double dref = kSurfaceTensionRefSpacing, h = support();
  const double sigma = double(surface_tension) / (dref * dref);  // N/m: the pressure jump per unit curvature
  return double(capillary_cfl) * std::sqrt(double(rest_density) * h * h * h / (2.0 * std::numbers::pi * sigma));
}

Status SolverParams::validate(std::string_view p) const {
  FF_CHECK(core::validate_fields(*this, p));
  if (!(max_iterations >= iterations))
    return param_error(fmt::format("{}.max_iterations = {} is outside [{}, 1000] (at least iterations)", p, max_iterations,
                                   iterations));
  return {};
}

Status Domain::validate(float r, std::string_view p) const {
  FF_CHECK(core::validate_fields(*this, p));
  for (int a = 0; a < 3; ++a)
    if (!(max[a] - min[a] >= 4.0f * r))
      return param_error(fmt::format("{}: max[{}] − min[{}] = {} must be at least 4 particle radii ({})", p, a, a,
                                     max[a] - min[a], 4.0f * r));
  return {};
}

Status FluidSource::validate(std::string_view p) const {
  FF_CHECK(core::validate_fields(*this, p));  // the velocity; the rest depends on the shape
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
