#include "surface/surface_params.h"

#include "core/params.h"

#include <fmt/format.h>

namespace ff::surface {

std::string_view extraction_name(Extraction e) { return core::choice_name(e); }

Result<Extraction> parse_extraction(std::string_view name) {
  if (const auto e = core::find_choice<Extraction>(name)) return *e;
  return param_error(fmt::format("'{}' is not a surface extraction (mc or rmt)", name));
}

Status SurfaceParams::validate(std::string_view path) const {
  FF_CHECK(core::validate_fields(*this, path));
  // The sparse grid evaluates each 8³-node block from the particles of its 27 neighbouring blocks only.
  if (!(kernel_radius <= 8.0f * cell_size))
    return param_error(
        fmt::format("{}.kernel_radius = {:g} d exceeds 8 cells ({:g} d): the sparse grid's blocks "
                    "see only their neighbours' particles",
                    path, kernel_radius, 8.0f * cell_size));
  if (extraction != Extraction::MarchingCubes && extraction != Extraction::MarchingTetrahedra)
    return param_error(fmt::format("{}.extraction is not a known extraction", path));
  if (reduction != Reduction::None && reduction != Reduction::Cluster)
    return param_error(fmt::format("{}.reduction is not a known reduction", path));
  return {};
}

}  // namespace ff::surface
