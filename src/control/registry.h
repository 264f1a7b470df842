#pragma once
// The one table of controllers (docs/ARCHITECTURE.md, "A controller"). A row is a controller's parameter struct P, which carries
// its name, summary and approximation flag (P::info, control/controller_info.h), its field list (P::fields) and,
// through its header, its factory make_controller(targets, ctx, const P&). Everything else — the scene reader and
// writer, --controller, --help, `compare`, `serve` and the viewer's list — reads this table, so adding a controller
// is its own files plus one row here.
#include "control/adaptive.h"
#include "control/adaptive_params.h"
#include "control/control_context.h"
#include "control/controller_info.h"
#include "control/lcat.h"
#include "control/pbfc.h"
#include "control/rscf.h"
#include "control/thuerey.h"
#include "control/weighted.h"
#include "core/fields.h"
#include "sim/controller.h"

#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <tuple>
#include <vector>

namespace ff::control {

/// `none`: plain PBF, the reference. It has no parameters.
struct NoneParams {
  static constexpr ControllerInfo info{"none", "plain PBF, no control (reference)", false};
  template <class S, class F>
  static void fields(S&, F&&) {}
};
Result<std::unique_ptr<sim::Controller>> make_controller(std::vector<ControlTarget> targets, const ControlContext& ctx,
                                                         const NoneParams& params);

/// The table, in the order of `fluidform compare`'s rows: the paper's method, the reference, then the baselines of
/// METHOD.md §b (Table 3's columns), the approximations last.
using ControllerTable = std::tuple<AdaptiveParams, NoneParams, ThuereyParams, PbfcParams, WeightedParams, RscfParams,
                                   LcatParams>;

/// The controller of a scene: its name and the parameters of every controller (only the named one is used; a scene
/// may set several, so that switching the controller keeps each one's settings).
struct ControllerSpec {
  std::string name = "adaptive";  ///< a table name; "none" runs plain PBF
  ControllerTable params;

  template <class P>
  P& get() { return std::get<P>(params); }
  template <class P>
  const P& get() const { return std::get<P>(params); }

  template <class S, class F>
  static void fields(S& s, F&& f) {
    f("name", s.name, core::plain("the shape controller (fluidform --help lists them)"));
    std::apply([&](auto&... p) { (f(std::remove_cvref_t<decltype(p)>::info.name, p, core::plain(std::remove_cvref_t<decltype(p)>::info.summary)), ...); },
               s.params);
  }
  Status validate(std::string_view path = "controller") const;
};

/// Every controller in table order.
std::span<const ControllerInfo> registry();
/// The row named `name`, or nullptr.
const ControllerInfo* find_controller(std::string_view name);
/// "adaptive, none, ..." for messages.
std::string controller_names();

/// Makes the controller `spec.name` for these targets. Errors: unknown name (with the list), bad parameters,
/// a controller that needs targets given none.
Result<std::unique_ptr<sim::Controller>> make_controller(const ControllerSpec& spec, std::vector<ControlTarget> targets,
                                                         const ControlContext& ctx);

}  // namespace ff::control
