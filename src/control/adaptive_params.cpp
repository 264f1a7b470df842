#include "control/adaptive_params.h"

namespace ff::control {

std::string_view bond_radius_name(BondRadius b) { return core::choice_name(b); }

std::optional<BondRadius> parse_bond_radius(std::string_view s) {
  if (const auto b = core::find_choice<BondRadius>(s)) return *b;
  return std::nullopt;
}

}  // namespace ff::control
