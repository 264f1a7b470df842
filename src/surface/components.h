#pragma once
// Removal of tiny floating components (spray droplets, lone clumps) and of cavities (bubbles): a closed
// component enclosing less than a minimum volume, or enclosing air, is dropped. Volume, not triangle count,
// because triangle counts change with the grid and the decimation while the fluid a droplet holds does not.
#include "core/types.h"
#include "io/triangle_mesh.h"

#include <vector>

namespace ff::surface {

struct ComponentCleanup {
  std::size_t removed_components = 0;
  std::size_t removed_triangles = 0;
  std::vector<Index> vertex_map;  ///< old → new vertex index, kInvalidIndex when removed (empty: nothing removed)
};

/// Drops every component whose |signed volume| is below `min_volume` (m³), and with `remove_cavities` every
/// component of negative volume (on an outward-wound closed mesh: the wall of a bubble). Keeps the order of
/// what remains.
ComponentCleanup remove_small_components(io::TriangleMesh& mesh, double min_volume, bool remove_cavities);

}  // namespace ff::surface
