#include "control/registry.h"

#include <fmt/format.h>

#include <array>

namespace ff::control {

namespace {
constexpr std::array<RegistryEntry, 2> kRegistry{{
    {"adaptive", "the paper (Zhou et al.): adaptive weights, unilateral density control, bond breaking, boundary correction", false},
    {"none", "plain PBF, no control (reference)", false},
}};
}  // namespace

std::span<const RegistryEntry> registry() { return kRegistry; }

const RegistryEntry* find_controller(std::string_view name) {
  for (const auto& e : kRegistry)
    if (e.name == name) return &e;
  return nullptr;
}

std::string controller_names() {
  std::string s;
  for (const auto& e : kRegistry) s += (s.empty() ? "" : ", ") + std::string(e.name);
  return s;
}

Status ControllerSpec::validate(std::string_view path) const {
  if (!find_controller(name))
    return param_error(fmt::format("{}.name = \"{}\" is not one of: {}", path, name, controller_names()));
  return adaptive.validate(fmt::format("{}.adaptive", path));
}

Result<std::unique_ptr<sim::Controller>> make_controller(const ControllerSpec& spec, std::vector<ControlTarget> targets,
                                                         const ControlContext& ctx) {
  FF_CHECK(spec.validate());
  if (spec.name == "none") return std::unique_ptr<sim::Controller>(std::make_unique<sim::NoController>());
  if (spec.name == "adaptive") {
    FF_TRY(auto c, AdaptiveController::create(std::move(targets), ctx, spec.adaptive));
    return std::unique_ptr<sim::Controller>(std::move(c));
  }
  return param_error(fmt::format("controller \"{}\" is not one of: {}", spec.name, controller_names()));
}

}  // namespace ff::control
