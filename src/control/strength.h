#pragma once
// A target's control strength over time (issue 19 item 4): keyframes of a value in [0, 1], interpolated linearly,
// holding the first value before the first key and the last after the last. 1 holds the fluid in the shape, 0
// releases it as free liquid (the controller then adds exactly nothing: no bonds, no force, no correction), values
// between soften every part of the control in proportion (adaptive; the baselines act at any strength above 0 and
// release at 0). No keys: 1 at every time. "Form, hold, release" is [{0, 1}, {T, 1}, {T + 0.5, 0}]; "release, then
// re-form" adds {T2, 0}, {T2 + 0.5, 1}.
#include "core/error.h"
#include "core/fields.h"

#include <string_view>
#include <vector>

namespace ff::control {

struct StrengthKey {
  double time = 0.0;   ///< s, ≥ 0, strictly increasing along the list
  float value = 1.0f;  ///< [0, 1]: 0 releases, 1 holds
  template <class S, class F>
  static void fields(S& s, F&& f) {
    using namespace core;
    f("time", s.time, required(closed(0.0, 1e6, "s, strictly increasing along the list")));
    f("value", s.value, required(closed(0.0, 1.0, "0 releases the fluid, 1 holds it, between softens")));
  }
};

struct StrengthTrack {
  std::vector<StrengthKey> keys;
  /// The strength at `time`, in [0, 1] (1 without keys).
  float at(double time) const;
  /// Keys in range and at strictly increasing times; errors name `path`.strength[k].
  Status validate(std::string_view path) const;
};

}  // namespace ff::control
