#include "control/registry.h"

#include <fmt/format.h>

#include <array>

namespace ff::control {

namespace {
// Table order = the order of `fluidform compare`'s rows: the paper's method, the reference, then the baselines
// of METHOD.md §b (Table 3's columns), the approximations last.
constexpr std::array<RegistryEntry, 7> kRegistry{{
    {"adaptive", "the paper (Zhou et al.): adaptive weights, unilateral density control, bond breaking, boundary correction", false},
    {"none", "plain PBF, no control (reference)", false},
    {"thuerey", "Thuerey et al. 2006: attraction by fill level + detail-preserving velocity control", false},
    {"pbfc", "Zhang et al. 2015 (PBFC): bilateral density constraint, adaptive spring, velocity constraint", false},
    {"weighted", "Zhou et al. (ref. [60]): colour-field weights, bilateral density to rho_c, adaptive spring", true},
    {"rscf", "Lu et al. 2019 (rigging-skinning): Shepard-skinned rig position and velocity, no density term", true},
    {"lcat", "Schoentgen et al. 2020 (animation templates): template density and velocity forces, temporary particles", true},
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
  FF_CHECK(adaptive.validate(fmt::format("{}.adaptive", path)));
  FF_CHECK(thuerey.validate(fmt::format("{}.thuerey", path)));
  FF_CHECK(pbfc.validate(fmt::format("{}.pbfc", path)));
  FF_CHECK(weighted.validate(fmt::format("{}.weighted", path)));
  FF_CHECK(rscf.validate(fmt::format("{}.rscf", path)));
  return lcat.validate(fmt::format("{}.lcat", path));
}

Result<std::unique_ptr<sim::Controller>> make_controller(const ControllerSpec& spec, std::vector<ControlTarget> targets,
                                                         const ControlContext& ctx) {
  FF_CHECK(spec.validate());
  if (spec.name == "none") return std::unique_ptr<sim::Controller>(std::make_unique<sim::NoController>());
  if (spec.name == "adaptive") {
    FF_TRY(auto c, AdaptiveController::create(std::move(targets), ctx, spec.adaptive));
    return std::unique_ptr<sim::Controller>(std::move(c));
  }
  auto up = [](auto r) -> Result<std::unique_ptr<sim::Controller>> {
    if (!r) return r.error();
    return std::unique_ptr<sim::Controller>(std::move(*r));
  };
  if (spec.name == "thuerey") return up(ThuereyController::create(std::move(targets), ctx, spec.thuerey));
  if (spec.name == "pbfc") return make_pbfc(std::move(targets), ctx, spec.pbfc);
  if (spec.name == "weighted") return make_weighted(std::move(targets), ctx, spec.weighted);
  if (spec.name == "rscf") return up(RscfController::create(std::move(targets), ctx, spec.rscf));
  if (spec.name == "lcat") return up(LcatController::create(std::move(targets), ctx, spec.lcat));
  return param_error(fmt::format("controller \"{}\" is not one of: {}", spec.name, controller_names()));
}

}  // namespace ff::control
