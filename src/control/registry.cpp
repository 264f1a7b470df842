#include "control/registry.h"

#include "core/printable.h"

#include <fmt/format.h>

#include <array>

namespace ff::control {

namespace {
constexpr auto kInfos = std::apply([](const auto&... p) {
  return std::array<ControllerInfo, sizeof...(p)>{std::remove_cvref_t<decltype(p)>::info...};
}, ControllerTable{});
}  // namespace

Result<std::unique_ptr<sim::Controller>> make_controller(std::vector<ControlTarget>, const ControlContext&, const NoneParams&) {
  return std::unique_ptr<sim::Controller>(std::make_unique<sim::NoController>());
}

std::span<const ControllerInfo> registry() { return kInfos; }

const ControllerInfo* find_controller(std::string_view name) {
  for (const auto& e : kInfos)
    if (e.name == name) return &e;
  return nullptr;
}

std::string controller_names() {
  std::string s;
  for (const auto& e : kInfos) s += (s.empty() ? "" : ", ") + std::string(e.name);
  return s;
}

Status ControllerSpec::validate(std::string_view path) const {
  if (!find_controller(name))
    return param_error(fmt::format("{}.name = \"{}\" is not one of: {}", path, printable(name), controller_names()));
  Status st;
  std::apply([&](const auto&... p) {
    ((st = st.ok() ? core::validate_fields(p, fmt::format("{}.{}", path, p.info.name)) : st), ...);
  }, params);
  return st;
}

Result<std::unique_ptr<sim::Controller>> make_controller(const ControllerSpec& spec, std::vector<ControlTarget> targets,
                                                         const ControlContext& ctx) {
  FF_CHECK(spec.validate());
  Result<std::unique_ptr<sim::Controller>> made = param_error(
      fmt::format("controller \"{}\" is not one of: {}", printable(spec.name), controller_names()));
  std::apply([&](const auto&... p) {
    ((p.info.name == spec.name ? (void)(made = make_controller(std::move(targets), ctx, p)) : void()), ...);
  }, spec.params);
  return made;
}

}  // namespace ff::control
