#include "sampling/sampling_params.h"

#include "core/params.h"

#include <fmt/format.h>

namespace ff::sampling {

std::string_view method_name(Method m) {
  switch (m) {
    case Method::BlueNoise: return "blue-noise";
    case Method::Voxel: return "voxel";
    case Method::Surface: return "surface";
  }
  return "?";
}

std::optional<Method> parse_method(std::string_view name) {
  for (Method m : {Method::BlueNoise, Method::Voxel, Method::Surface})
    if (method_name(m) == name) return m;
  return std::nullopt;
}

Status SparseParams::validate(std::string_view path) const {
  FF_CHECK(core::check_range(path, "drop_fraction", drop_fraction, 0.0, 0.99));
  for (std::size_t i = 0; i < drop_boxes.size(); ++i) {
    const auto& b = drop_boxes[i];
    const std::string key = fmt::format("drop_boxes[{}]", i);
    FF_CHECK(core::check_vec(path, key + ".min", b.min, -1e6, 1e6));
    FF_CHECK(core::check_vec(path, key + ".max", b.max, -1e6, 1e6));
    if (b.empty()) return param_error(fmt::format("{}.{} is empty (min > max on an axis)", path, key));
  }
  return {};
}

Status SamplingParams::validate(std::string_view path) const {
  FF_CHECK(core::check_range(path, "spacing", spacing, 0.0, 1e3));
  FF_CHECK(core::check_range(path, "auto_count", double(auto_count), 100.0, 1e8));
  FF_CHECK(core::check_range(path, "relax_steps", relax_steps, 0, 10000));
  FF_CHECK(core::check_range(path, "support_factor", support_factor, 1.5, 8.0));
  FF_CHECK(core::check_range(path, "phi_offset", phi_offset, 0.0, 1.0));
  FF_CHECK(core::check_range(path, "rest_density", rest_density, 0.0, 1e5, core::Bound::Open));
  FF_CHECK(core::check_range(path, "max_samples", double(max_samples), 1.0, 1e9));
  return sparse.validate(fmt::format("{}.sparse", path));
}

}  // namespace ff::sampling
