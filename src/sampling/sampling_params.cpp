#include "sampling/sampling_params.h"

#include "core/params.h"

#include <fmt/format.h>

namespace ff::sampling {

std::string_view method_name(Method m) { return core::choice_name(m); }

std::optional<Method> parse_method(std::string_view name) {
  if (const auto m = core::find_choice<Method>(name)) return *m;
  return std::nullopt;
}

Status SparseParams::validate(std::string_view path) const {
  FF_CHECK(core::validate_fields(*this, path));
  for (std::size_t i = 0; i < drop_boxes.size(); ++i)
    if (drop_boxes[i].empty()) return param_error(fmt::format("{}.drop_boxes[{}] is empty (min > max on an axis)", path, i));
  return {};
}

Status SamplingParams::validate(std::string_view path) const {
  FF_CHECK(core::validate_fields(*this, path));  // the sparse block included
  return core::check_range(path, "rest_density", rest_density, 0.0, 1e5, core::Bound::Open);
}

}  // namespace ff::sampling
