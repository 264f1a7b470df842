#pragma once
// Range checks for parameter structs' validate(): one message shape everywhere,
//   "<path>.<key> = <value> is outside <range>"
// written as !(lo <= x && x <= hi) so that NaN fails every check.
#include "core/error.h"
#include "core/types.h"

#include <fmt/format.h>

#include <cmath>
#include <string_view>

namespace ff::core {

enum class Bound { Closed, Open };

inline std::string format_range(double lo, double hi, Bound lb, Bound hb) {
  return fmt::format("{}{:g}, {:g}{}", lb == Bound::Closed ? '[' : '(', lo, hi, hb == Bound::Closed ? ']' : ')');
}

/// Checks lo ≤ value ≤ hi (or strict, per bound); the error names "path.key", the value and the range.
inline Status check_range(std::string_view path, std::string_view key, double value, double lo, double hi,
                          Bound lb = Bound::Closed, Bound hb = Bound::Closed) {
  const bool lo_ok = lb == Bound::Closed ? value >= lo : value > lo;
  const bool hi_ok = hb == Bound::Closed ? value <= hi : value < hi;
  if (lo_ok && hi_ok) return {};
  return param_error(fmt::format("{}.{} = {:.7g} is outside {}", path, key, value, format_range(lo, hi, lb, hb)));
}

/// Every component finite and within [lo, hi] (with `either_sign`, its magnitude: a scale may mirror).
inline Status check_vec(std::string_view path, std::string_view key, const Vec3f& v, double lo, double hi,
                        bool either_sign = false) {
  for (int a = 0; a < 3; ++a) {
    const double c = either_sign ? std::abs(double(v[a])) : double(v[a]);
    if (!(c >= lo && c <= hi))
      return param_error(fmt::format("{}.{} = [{}, {}, {}] is outside {}[{}, {}] in component {}", path, key, v.x(),
                                     v.y(), v.z(), either_sign ? "±" : "", lo, hi, a));
  }
  return {};
}

}  // namespace ff::core
