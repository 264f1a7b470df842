#include "control/strength.h"

#include "core/keys.h"

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
  return core::validate_keys(std::span<const StrengthKey>(keys), path, "strength", "key");
}

}  // namespace ff::control
