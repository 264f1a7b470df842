#pragma once
// Analytic shapes for the surface tests: particles on a cubic lattice inside the shape, the shape's signed
// distance, points on its surface, and mesh-to-surface distances (brute force, the oracle).
#include "core/types.h"
#include "io/triangle_mesh.h"

#include <functional>
#include <vector>

namespace ff::test {

/// Signed distance (m, negative inside) of an analytic shape.
using Sdf = std::function<float(const Vec3f&)>;

Sdf sphere_sdf(const Vec3f& centre, float radius);
/// Torus around the y axis through `centre`: tube centre radius `major`, tube radius `minor`.
Sdf torus_sdf(const Vec3f& centre, float major, float minor);

/// Lattice points i·d (i integer) with sdf < 0 inside the box [lo, hi].
std::vector<Vec3f> lattice_inside(const Sdf& sdf, const Vec3f& lo, const Vec3f& hi, float d);

/// About n points spread evenly on a sphere / torus surface.
std::vector<Vec3f> sphere_surface_points(const Vec3f& centre, float radius, int n);
std::vector<Vec3f> torus_surface_points(const Vec3f& centre, float major, float minor, int n_around, int n_tube);

/// Distance from p to the closest point of triangle (a, b, c).
float point_triangle_distance(const Vec3f& p, const Vec3f& a, const Vec3f& b, const Vec3f& c);

struct SurfaceDistances {
  /// |sdf| of the mesh: max over vertices and triangle centroids; mean over the area (centroid rule), so that
  /// meshes with different vertex densities compare fairly.
  float mesh_max = 0, mesh_mean = 0;
  float surface_max = 0, surface_mean = 0;  ///< distance from the true-surface points to the mesh triangles
};
SurfaceDistances surface_distances(const io::TriangleMesh& mesh, const Sdf& sdf, const std::vector<Vec3f>& truth);

/// A test shape: lattice particles at spacing d inside it, its SDF, points on its true surface, its genus.
struct AnalyticShape {
  const char* name;
  Sdf sdf;
  std::vector<Vec3f> particles;
  std::vector<Vec3f> truth;  // points on the true surface
  int genus;
};
/// Centre of the analytic shapes: off the lattice, so that they do not line up with it.
inline const Vec3f kShapeCentre(0.037f, 0.011f, -0.023f);
/// The sphere (radius 8 d) and torus (8 d around, 3.5 d tube) of the surface tests, at kShapeCentre.
AnalyticShape analytic_sphere(float d);
AnalyticShape analytic_torus(float d);

}  // namespace ff::test
