#pragma once
// How thin a target's thinnest parts are: the wall thickness along the inward normal at points spread over the
// surface, the one-ray shape diameter function of Shapira, Shamir & Cohen ("Consistent mesh partitioning and
// skeletonisation using the shape diameter function", Visual Computer 2008). A slab reads its thickness, a tube
// (round or square) its width, a sphere its diameter, a thick part its thickness across, also next to its edges
// (where an inscribed ball would read how far the edge is instead). A ray must land on a far side facing back (the
// normals at least ~143° apart, a wedge of at most ~37°: a blade is a wall): one that leaves through the neighbouring
// face of a blunter wedge (a tetrahedron's edge, 55°–71°) measures how near the edge it started, not a wall.
//
// The ray is sphere-traced with closest-point queries: from just below s it steps by the distance to the nearest
// surface, which doubles the depth while s's own side is nearest and lands on the far side when it comes near, so a
// ray takes ~log2(thickness / start) + a few queries.
//
// The points are spread over the surface by area (random_surface_points with a fixed seed: deterministic), and
// the thinnest part is a low percentile of their thicknesses: a few slivers do not decide it, a thin wall does.
#include "io/triangle_mesh.h"
#include "sampling/mesh_field.h"

#include <cstddef>
#include <optional>

namespace ff::sampling {

struct Thickness {
  float thinnest = 0.0f;        ///< m: the `percentile` quantile of the wall thickness over the surface, by area
  Vec3f where{Vec3f::Zero()};   ///< a surface point whose wall is that thin
  float median = 0.0f;          ///< m: the median wall thickness, for comparison (+inf: most points have no wall)
  double thin_area_share = 0.0; ///< share of the measured surface with a wall at most 1.5× `thinnest`
};

struct ThicknessParams {
  std::size_t points = 4096;  ///< surface points measured (each ~10–20 closest-point queries)
  double percentile = 0.02;   ///< the thinnest part: this share of the surface is thinner. (0, 1)
  float facing_back = -0.8f;  ///< a wall's far side faces back: cos of the angle between the normals, at most
};

/// The thinnest part of a closed target (`field` built from `mesh`); nullopt when less than `percentile` of its
/// surface is a wall (a tetrahedron, a mesh without area, an open sheet).
std::optional<Thickness> measure_thickness(const MeshField& field, const io::TriangleMesh& mesh,
                                           const ThicknessParams& params = {});

}  // namespace ff::sampling
