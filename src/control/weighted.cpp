#include "control/weighted.h"

#include <cmath>

namespace ff::control {

Result<std::unique_ptr<sim::Controller>> make_controller(std::vector<ControlTarget> targets, const ControlContext& ctx,
                                                       const WeightedParams& params) {
  FF_CHECK(params.validate());
  DensitySpringConfig cfg = density_spring_config(params, "weighted");
  cfg.kappa = params.kappa;
  cfg.velocity = cfg.velocity_moving = 0.0f;
  cfg.per_sample_density = true;
  FF_TRY(auto c, DensitySpringController::create(std::move(targets), ctx, std::move(cfg)));
  return std::unique_ptr<sim::Controller>(std::move(c));
}

}  // namespace ff::control
