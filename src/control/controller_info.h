#pragma once
// What the controller table (control/registry.h) says of each controller. Every controller's parameter struct P
// carries `static constexpr ControllerInfo info`, and its header declares the factory
//   Result<std::unique_ptr<sim::Controller>> make_controller(std::vector<ControlTarget>, const ControlContext&, const P&);
// so that the table row, `P`, is all the registry needs.
#include "core/error.h"
#include "sim/controller.h"

#include <memory>
#include <string_view>
#include <utility>

namespace ff::control {

struct ControllerInfo {
  std::string_view name;      ///< the scene's and the CLI's name
  std::string_view summary;   ///< one line for --help and tables
  bool approximation = false; ///< a documented approximation of a method whose details are not public (METHOD §b)
};

/// A controller made by its class's create() as the table's factory returns it.
template <class C>
Result<std::unique_ptr<sim::Controller>> as_controller(Result<std::unique_ptr<C>> made) {
  if (!made) return made.error();
  return std::unique_ptr<sim::Controller>(std::move(*made));
}

}  // namespace ff::control
