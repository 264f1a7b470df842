#include "control/adaptive_params.h"

#include "core/params.h"

namespace ff::control {

std::string_view bond_radius_name(BondRadius b) { return b == BondRadius::Paper ? "paper" : "over-full"; }

std::optional<BondRadius> parse_bond_radius(std::string_view s) {
  if (s == "paper") return BondRadius::Paper;
  if (s == "over-full") return BondRadius::OverFull;
  return std::nullopt;
}

Status AdaptiveParams::validate(std::string_view p) const {
  FF_CHECK(core::check_range(p, "alpha", alpha, 0.0, 2.0, core::Bound::Open));
  FF_CHECK(core::check_range(p, "epsilon", epsilon, 0.0, 100.0, core::Bound::Open));
  FF_CHECK(core::check_range(p, "clamp", clamp, 0.0, 1.0, core::Bound::Open));
  FF_CHECK(core::check_range(p, "gamma", gamma, 0.0, 1.0));
  FF_CHECK(core::check_range(p, "normal_threshold", normal_threshold, 0.0, 1.0));
  FF_CHECK(core::check_range(p, "gather_fill", gather_fill, 0.0, 1.0, core::Bound::Open));
  FF_CHECK(core::check_range(p, "gather_speed", gather_speed, 0.0, 1000.0, core::Bound::Open));
  FF_CHECK(core::check_range(p, "max_speed", max_speed, 0.0, 10000.0, core::Bound::Open));
  FF_CHECK(core::check_range(p, "gather_time", gather_time, 0.0, 10.0, core::Bound::Open));
  return {};
}

}  // namespace ff::control
