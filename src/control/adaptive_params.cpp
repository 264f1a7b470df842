#include "control/adaptive_params.h"

#include <algorithm>
#include <cmath>

namespace ff::control {

std::string_view bond_radius_name(BondRadius b) { return core::choice_name(b); }

std::optional<BondRadius> parse_bond_radius(std::string_view s) {
  if (const auto b = core::find_choice<BondRadius>(s)) return *b;
  return std::nullopt;
}

std::vector<float> speed_scales(const std::vector<std::uint8_t>& target, std::size_t targets, float reference) {
  std::vector<float> scale(targets, 1.0f);
  if (!(reference > 0.0f)) return scale;
  std::vector<std::size_t> count(targets, 0);
  for (const std::uint8_t t : target)
    if (t < targets) ++count[t];
  for (std::size_t t = 0; t < targets; ++t)
    scale[t] = std::max(1.0f, static_cast<float>(std::cbrt(static_cast<double>(count[t]) / reference)));
  return scale;
}

}  // namespace ff::control
