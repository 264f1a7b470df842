#pragma once
// Vertex reduction in the spirit of regularised marching tetrahedra (Treece, Prager & Gee 1999; METHOD.md §a.7
// "Reduction", §c.9): every marching-cubes vertex belongs to the grid node nearest to it along its edge; all
// vertices of one node merge into their mean, and triangles that lose a corner vanish. This leaves about one
// vertex per node next to the surface (a marching-cubes mesh has one per crossed edge) and removes the
// slivers marching cubes makes where the surface passes close to a node. The merged vertex can then be placed
// (reconstruct() projects it back onto the iso-surface). On marching_tetrahedra.h's mesh, whose vertices record
// their nearest node the same way, this is Treece et al.'s regularisation itself: together, RMT.
//
// Marching cubes' vertices of one node are not guaranteed to merge into a manifold, and a merge can fold a
// triangle over (on marching tetrahedra this is rare but happens too: 62 of ~24.7k merges undone on the
// lattice-filled bunny of surface_slow_test.cpp, none on the analytic sphere and torus). So merges are taken back
// where they hurt (METHOD: "reject a merge that would make an edge non-manifold"): after merging, every vertex
// that is not a clean closed fan, every triangle whose normal turned by more than 90° and every zero-area
// triangle marks the merged nodes around it as unmerged, and the mesh is rebuilt; this repeats until the mesh is
// clean. It terminates: each round unmerges at least one node, and with none merged the input comes back.
// Deterministic.
#include "io/triangle_mesh.h"

#include <cstdint>
#include <functional>
#include <span>

namespace ff::surface {

struct ClusterStats {
  std::size_t clusters_merged = 0;  ///< nodes whose vertices were merged
  std::size_t clusters_undone = 0;  ///< merges taken back
  int rounds = 0;                   ///< rebuilds needed to reach a clean mesh
};

/// Places a merged vertex given its cluster's mean (e.g. back onto the iso-surface: the mean of points on a
/// curved surface lies off it). Empty: the mean itself.
using PlaceVertex = std::function<Vec3f(const Vec3f&)>;

/// The reduced mesh of `mesh` (closed and manifold, as from marching cubes) given each vertex's cluster id
/// (equal ids merge; `no_cluster` never merges).
io::TriangleMesh cluster_reduce(const io::TriangleMesh& mesh, std::span<const std::uint64_t> cluster,
                                std::uint64_t no_cluster, const PlaceVertex& place = {}, ClusterStats* stats = nullptr);

}  // namespace ff::surface
