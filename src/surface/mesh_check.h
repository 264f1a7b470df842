#pragma once
// What an output mesh must be (docs/outputs.md): watertight (every edge has exactly two triangles), 2-manifold (every
// vertex's triangles form one fan), consistently oriented and outward (every edge used once in each direction,
// every component encloses a positive signed volume), no degenerate triangles. Plus what tests and logs want:
// Euler characteristic, genus and components. Used after every stage of reconstruct(), so a stage that breaks
// the mesh is caught and undone, and by the tests as the oracle.
#include "core/types.h"
#include "io/triangle_mesh.h"

#include <cstddef>
#include <string>
#include <vector>

namespace ff::surface {

struct MeshCheck {
  std::size_t vertices = 0, triangles = 0, edges = 0;  ///< edges: undirected, among valid triangles
  std::size_t boundary_edges = 0;                      ///< edges with one triangle
  std::size_t nonmanifold_edges = 0;                   ///< edges with more than two triangles
  std::size_t misoriented_edges = 0;                   ///< edges with two triangles that run it the same way
  std::size_t nonmanifold_vertices = 0;   ///< vertices whose link is not a single cycle (bow-ties, cones, fins)
  std::size_t unreferenced_vertices = 0;  ///< vertices no triangle uses
  std::size_t degenerate_triangles = 0;   ///< repeated index, zero area or a non-finite vertex
  std::size_t invalid_triangles = 0;      ///< index out of range (ignored by the other counts)
  std::size_t components = 0;
  std::size_t inward_components = 0;  ///< components with signed volume ≤ 0
  double volume = 0.0;                ///< total signed volume, m³ (positive for outward winding)
  long long euler = 0;                ///< χ = V − E + F over referenced vertices
  int genus = -1;                     ///< Σ over components of g = (2 − χ_c)/2; −1 unless closed and manifold

  bool watertight() const { return boundary_edges == 0 && invalid_triangles == 0; }
  bool manifold() const { return nonmanifold_edges == 0 && nonmanifold_vertices == 0; }
  bool oriented() const { return misoriented_edges == 0; }
  bool outward() const { return inward_components == 0; }
  bool no_degenerate() const { return degenerate_triangles == 0; }
  /// All of the above, and no unused vertices. An empty mesh is ok.
  bool ok() const {
    return watertight() && manifold() && oriented() && outward() && no_degenerate() && unreferenced_vertices == 0;
  }
  /// ok(), except that components enclosing air (bubbles inside the fluid, wound inward as they should be) are
  /// allowed as long as the total volume is positive.
  bool ok_allowing_cavities() const {
    return watertight() && manifold() && oriented() && volume > 0.0 && no_degenerate() && unreferenced_vertices == 0;
  }
  /// One line for logs and test failures.
  std::string summary() const;
};

/// Checks `mesh`. Cost O(V + F) plus O(k²) per vertex of degree k; parallel over vertices, deterministic.
MeshCheck check_mesh(const io::TriangleMesh& mesh);

/// Vertices where the mesh is not a closed, oriented 2-manifold: ends of edges without exactly one triangle
/// each way, and vertices whose link is not one cycle. Increasing order.
std::vector<Index> defect_vertices(const io::TriangleMesh& mesh);

}  // namespace ff::surface
