#include "control/pbfc.h"

#include <cmath>

namespace ff::control {

Result<std::unique_ptr<sim::Controller>> make_controller(std::vector<ControlTarget> targets, const ControlContext& ctx,
                                                   const PbfcParams& params) {
  FF_CHECK(params.validate());
  DensitySpringConfig cfg = density_spring_config(params, "pbfc");
  cfg.velocity = params.velocity, cfg.velocity_moving = params.velocity_moving;
  FF_TRY(auto c, DensitySpringController::create(std::move(targets), ctx, std::move(cfg)));
  return std::unique_ptr<sim::Controller>(std::move(c));
}

}  // namespace ff::control
