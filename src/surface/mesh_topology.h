#pragma once
// Connectivity of a triangle mesh, built in O(V + F) and shared by the checks, the smoothing and the
// clean-up: each vertex's outgoing half-edges (its star) and the mesh's connected components.
#include "core/types.h"
#include "io/triangle_mesh.h"

#include <cstddef>
#include <vector>

namespace ff::surface {

/// Outgoing half-edges per vertex (CSR). Triangle (a, b, c) gives a → b, b → c, c → a; for the half-edge
/// v → to[h] of triangle tri[h], third[h] is the triangle's remaining vertex, so (to[h], third[h]) is an edge of
/// v's link. Half-edges of a vertex are in triangle order. On a closed manifold mesh a vertex's `to` values are
/// exactly its 1-ring. Triangles with an index out of range are skipped.
struct VertexStar {
  std::vector<Index> start;  ///< size V + 1: vertex v owns half-edges [start[v], start[v + 1])
  std::vector<Index> to, third, tri;

  std::size_t degree(Index v) const { return start[v + 1] - start[v]; }
};
VertexStar vertex_star(const io::TriangleMesh& mesh);

/// Connected components through shared vertices: a component id per vertex (kInvalidIndex for a vertex no
/// triangle uses), numbered in order of each component's first triangle.
struct Components {
  std::vector<Index> of_vertex;
  std::size_t count = 0;
};
Components connected_components(const io::TriangleMesh& mesh);

/// Keeps the triangles with keep[t] != 0 and the vertices they use (in their old order). Returns the old →
/// new vertex map (kInvalidIndex for dropped vertices).
std::vector<Index> keep_triangles(io::TriangleMesh& mesh, const std::vector<unsigned char>& keep);

}  // namespace ff::surface
