#pragma once
// The one check of a list of timed keys (a target's keyframes, a strength track): each key valid by its own field
// list (core/fields.h), and the times strictly increasing along the list.
#include "core/error.h"
#include "core/fields.h"

#include <fmt/format.h>

#include <span>
#include <string_view>

namespace ff::core {

/// `keys` (each with a `double time`) checked as `path`.`list`[k]: every field in range, and each time later than the
/// one before it (an error calls that one "the `what` before it").
template <class Key>
Status validate_keys(std::span<const Key> keys, std::string_view path, std::string_view list, std::string_view what) {
  for (std::size_t k = 0; k < keys.size(); ++k) {
    const auto p = fmt::format("{}.{}[{}]", path, list, k);
    FF_CHECK(validate_fields(keys[k], p));
    if (k > 0 && !(keys[k].time > keys[k - 1].time))
      return param_error(fmt::format("{}.time = {} must be later than the {} before it ({})", p, keys[k].time, what,
                                     keys[k - 1].time));
  }
  return {};
}

}  // namespace ff::core
