#pragma once
// The one table of controllers (DESIGN.md `control/`): every controller is listed here with its name and
// a one-line description, and made through make_controller(). Scene files and `--controller` select by name.
#include "control/adaptive.h"
#include "control/adaptive_params.h"
#include "control/control_context.h"
#include "control/lcat.h"
#include "control/pbfc.h"
#include "control/rscf.h"
#include "control/thuerey.h"
#include "control/weighted.h"
#include "sim/controller.h"

#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace ff::control {

/// The controller of a scene and the parameters of each kind (only the chosen one is used).
struct ControllerSpec {
  std::string name = "adaptive";  ///< a registry name; "none" runs plain PBF
  AdaptiveParams adaptive;
  ThuereyParams thuerey;
  PbfcParams pbfc;
  WeightedParams weighted;
  RscfParams rscf;
  LcatParams lcat;
  Status validate(std::string_view path = "controller") const;
};

struct RegistryEntry {
  std::string_view name;
  std::string_view summary;   ///< for --help and tables
  bool approximation = false; ///< a documented approximation of a method whose details are not public (METHOD §b)
};

/// Every registered controller, in table order.
std::span<const RegistryEntry> registry();
/// The entry named `name`, or nullptr.
const RegistryEntry* find_controller(std::string_view name);
/// "adaptive, none, ..." for messages.
std::string controller_names();

/// Makes the controller `spec.name` for these targets. Errors: unknown name (with the list), bad parameters,
/// a controller that needs targets given none.
Result<std::unique_ptr<sim::Controller>> make_controller(const ControllerSpec& spec, std::vector<ControlTarget> targets,
                                                         const ControlContext& ctx);

}  // namespace ff::control
