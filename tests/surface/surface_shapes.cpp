#include "surface/surface_shapes.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace ff::test {

Sdf sphere_sdf(const Vec3f& centre, float radius) {
  return [=](const Vec3f& p) { return (p - centre).norm() - radius; };
}

Sdf torus_sdf(const Vec3f& centre, float major, float minor) {
  return [=](const Vec3f& p) {
    const Vec3f q = p - centre;
    const float ring = std::sqrt(q.x() * q.x() + q.z() * q.z()) - major;
    return std::sqrt(ring * ring + q.y() * q.y()) - minor;
  };
}

std::vector<Vec3f> lattice_inside(const Sdf& sdf, const Vec3f& lo, const Vec3f& hi, float d) {
  std::vector<Vec3f> out;
  const Eigen::Vector3i a = (lo / d).array().floor().cast<int>(), b = (hi / d).array().ceil().cast<int>();
  for (int k = a.z(); k <= b.z(); ++k)
    for (int j = a.y(); j <= b.y(); ++j)
      for (int i = a.x(); i <= b.x(); ++i) {
        const Vec3f p(float(i) * d, float(j) * d, float(k) * d);
        if (sdf(p) < 0.0f) out.push_back(p);
      }
  return out;
}

std::vector<Vec3f> sphere_surface_points(const Vec3f& centre, float radius, int n) {
  std::vector<Vec3f> out;
  const double golden = std::numbers::pi * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < n; ++i) {
    const double y = 1.0 - 2.0 * (i + 0.5) / n, r = std::sqrt(1.0 - y * y), t = golden * i;
    out.push_back(centre + radius * Vec3f(float(r * std::cos(t)), float(y), float(r * std::sin(t))));
  }
  return out;
}

std::vector<Vec3f> torus_surface_points(const Vec3f& centre, float major, float minor, int n_around, int n_tube) {
  std::vector<Vec3f> out;
  for (int i = 0; i < n_around; ++i)
    for (int j = 0; j < n_tube; ++j) {
      const double u = 2.0 * std::numbers::pi * (i + 0.5) / n_around, v = 2.0 * std::numbers::pi * (j + 0.25) / n_tube;
      const double r = major + minor * std::cos(v);
      out.push_back(centre + Vec3f(float(r * std::cos(u)), float(minor * std::sin(v)), float(r * std::sin(u))));
    }
  return out;
}

float point_triangle_distance(const Vec3f& p, const Vec3f& a, const Vec3f& b, const Vec3f& c) {
  // Closest point by Voronoi regions of the triangle (vertices, edges, face), in double for robustness.
  const Vec3d P = p.cast<double>(), A = a.cast<double>(), B = b.cast<double>(), C = c.cast<double>();
  const Vec3d ab = B - A, ac = C - A, ap = P - A;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return float((P - A).norm());
  const Vec3d bp = P - B;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return float((P - B).norm());
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return float((P - (A + ab * (d1 / (d1 - d3)))).norm());
  const Vec3d cp = P - C;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return float((P - C).norm());
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return float((P - (A + ac * (d2 / (d2 - d6)))).norm());
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
    return float((P - (B + (C - B) * ((d4 - d3) / ((d4 - d3) + (d5 - d6))))).norm());
  const double den = 1.0 / (va + vb + vc);
  return float((P - (A + ab * (vb * den) + ac * (vc * den))).norm());
}

SurfaceDistances surface_distances(const io::TriangleMesh& mesh, const Sdf& sdf, const std::vector<Vec3f>& truth) {
  SurfaceDistances s;
  if (mesh.vertices.empty()) {
    s.mesh_max = s.surface_max = std::numeric_limits<float>::infinity();
    return s;
  }
  for (const Vec3f& v : mesh.vertices) s.mesh_max = std::max(s.mesh_max, std::abs(sdf(v)));
  double sum = 0.0, area = 0.0;
  for (const auto& t : mesh.triangles) {
    const Vec3f &a = mesh.vertices[t[0]], &b = mesh.vertices[t[1]], &c = mesh.vertices[t[2]];
    const float e = std::abs(sdf((a + b + c) / 3.0f));
    const double w = 0.5 * double((b - a).cross(c - a).norm());
    s.mesh_max = std::max(s.mesh_max, e);
    sum += w * e;
    area += w;
  }
  s.mesh_mean = area > 0.0 ? float(sum / area) : 0.0f;
  // Triangle bounding spheres prune the brute-force search.
  std::vector<Vec3f> centre(mesh.triangles.size());
  std::vector<float> radius(mesh.triangles.size());
  for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
    const auto& t = mesh.triangles[f];
    centre[f] = (mesh.vertices[t[0]] + mesh.vertices[t[1]] + mesh.vertices[t[2]]) / 3.0f;
    radius[f] = 0.0f;
    for (const Index v : t) radius[f] = std::max(radius[f], (mesh.vertices[v] - centre[f]).norm());
  }
  sum = 0.0;
  for (const Vec3f& p : truth) {
    float best = std::numeric_limits<float>::infinity();
    for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
      if ((p - centre[f]).norm() - radius[f] >= best) continue;
      const auto& t = mesh.triangles[f];
      best = std::min(best, point_triangle_distance(p, mesh.vertices[t[0]], mesh.vertices[t[1]], mesh.vertices[t[2]]));
    }
    s.surface_max = std::max(s.surface_max, best);
    sum += best;
  }
  s.surface_mean = truth.empty() ? 0.0f : float(sum / double(truth.size()));
  return s;
}

AnalyticShape analytic_sphere(float d) {
  const float r = 8.0f * d;
  auto sdf = sphere_sdf(kShapeCentre, r);
  return {"sphere", sdf, lattice_inside(sdf, kShapeCentre - Vec3f::Constant(r), kShapeCentre + Vec3f::Constant(r), d),
          sphere_surface_points(kShapeCentre, r, 2000), 0};
}

AnalyticShape analytic_torus(float d) {
  const float big = 8.0f * d, small = 3.5f * d;
  auto sdf = torus_sdf(kShapeCentre, big, small);
  const Vec3f ext(big + small, small, big + small);
  return {"torus", sdf, lattice_inside(sdf, kShapeCentre - ext, kShapeCentre + ext, d),
          torus_surface_points(kShapeCentre, big, small, 80, 25), 1};
}

}  // namespace ff::test
