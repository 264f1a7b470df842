#pragma once
// Marching cubes on the sparse field (METHOD.md §c.8) with shared (welded) vertices: one vertex per grid edge
// the surface crosses, numbered per block (a bitset of the block's crossed edges and its prefix counts), so
// that the up to four cubes around an edge, in up to four blocks, name the same vertex without a hash map.
// The case table is mc_table.h (ambiguous faces by the asymptotic decider: watertight by construction).
//
// Each vertex also records the grid node nearest to it along its edge: the "cell" of Treece et al.'s
// regularisation (METHOD.md §c.9), which cluster_reduce.h merges over.
#include "core/error.h"
#include "io/triangle_mesh.h"
#include "surface/sparse_field.h"

#include <cstdint>
#include <limits>
#include <vector>

namespace ff::surface {

/// No regularisation cell (loop centres of mc_table.h).
inline constexpr std::uint64_t kNoCluster = std::numeric_limits<std::uint64_t>::max();

struct McMesh {
  io::TriangleMesh mesh;               ///< welded, closed, wound counter-clockwise seen from outside
  std::vector<std::uint64_t> cluster;  ///< per vertex: id of its nearest grid node, or kNoCluster
  std::size_t centre_vertices = 0;     ///< added loop centres (ambiguous configurations)
};

/// Vertices are placed by linear interpolation along the edge, kept 1 % of a cell away from either node so
/// that no two vertices coincide (which would make zero-area triangles).
/// Errors: Numerical when the blocks disagree about an edge (a bug; never expected), or more than 2^31 vertices.
Result<McMesh> marching_cubes(const SparseField& field);

}  // namespace ff::surface
