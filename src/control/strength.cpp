#include "control/strength.h"

#include <fmt/format.h>

namespace ff::control {

float StrengthTrack::at(double time) const {
  if (keys.empty()) return 1.0f;
  if (!(time > keys.front().time)) return keys.front().value;
  if (time >= keys.back().time) return keys.back().value;
  std::size_t k = 1;
  while (keys[k].time <= time) ++k;
  const StrengthKey& a = keys[k - 1];
  const StrengthKey& b = keys[k];
  const float u = static_cast<float>((time - a.time) / (b.time - a.time));
  // Exactly the keys' values at the keys, and never outside [0, 1] between them.
  const float s = a.value + u * (b.value - a.value);
  return s < 0.0f ? 0.0f : (s > 1.0f ? 1.0f : s);
}

Status StrengthTrack::validate(std::string_view path) const {
  for (std::size_t k = 0; k < keys.size(); ++k) {
    const auto p = fmt::format("{}.strength[{}]", path, k);
    FF_CHECK(core::validate_fields(keys[k], p));
    if (k > 0 && !(keys[k].time > keys[k - 1].time))
      return param_error(fmt::format("{}.time = {} must be later than the key before it ({})", p, keys[k].time,
                                     keys[k - 1].time));
  }
  return {};
}

}  // namespace ff::control
