#include "surface/surface_params.h"

#include "core/params.h"

#include <fmt/format.h>

namespace ff::surface {

std::string_view extraction_name(Extraction e) {
  return e == Extraction::MarchingTetrahedra ? "rmt" : "mc";
}

Result<Extraction> parse_extraction(std::string_view name) {
  if (name == "mc") return Extraction::MarchingCubes;
  if (name == "rmt") return Extraction::MarchingTetrahedra;
  return param_error(fmt::format("'{}' is not a surface extraction (mc or rmt)", name));
}

Status SurfaceParams::validate(std::string_view path) const {
  FF_CHECK(core::check_range(path, "cell_size", cell_size, 0.05, 4.0));
  FF_CHECK(core::check_range(path, "kernel_radius", kernel_radius, 0.5, 8.0));
  FF_CHECK(core::check_range(path, "particle_volume", particle_volume, 0.0, 10.0, core::Bound::Open));
  FF_CHECK(core::check_range(path, "iso", iso, 0.0, 1.0, core::Bound::Open, core::Bound::Open));
  FF_CHECK(core::check_range(path, "smoothing_passes", smoothing_passes, 0, 100));
  FF_CHECK(core::check_range(path, "smoothing_beta", smoothing_beta, 0.0, 1.0));
  FF_CHECK(core::check_range(path, "smoothing_radius", smoothing_radius, 0.5, 8.0));
  FF_CHECK(core::check_range(path, "smoothing_inflate", smoothing_inflate, 0.0, 1.0));
  FF_CHECK(core::check_range(path, "decimate_error", decimate_error, 0.0, 10.0));
  FF_CHECK(core::check_range(path, "max_triangles", double(max_triangles), 0.0, 1e9));
  FF_CHECK(core::check_range(path, "min_component_volume", min_component_volume, 0.0, 1e9));
  FF_CHECK(core::check_range(path, "max_blocks", double(max_blocks), 1.0, 1e9));
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
