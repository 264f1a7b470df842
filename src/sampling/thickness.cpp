#include "sampling/thickness.h"

#include "core/parallel.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace ff::sampling {
namespace {

// Point k of n spread over the surface by area: the k-th share of the cumulative area picks the triangle, the R2
// sequence (Roberts 2018) the barycentric coordinates inside it.
Vec3f surface_point(const io::TriangleMesh& mesh, const std::vector<double>& cumulative, std::size_t k, std::size_t n) {
  const double u = (double(k) + 0.5) / double(n) * cumulative.back();
  const auto t = static_cast<std::size_t>(std::upper_bound(cumulative.begin(), cumulative.end(), u) - cumulative.begin());
  const auto& tri = mesh.triangles[std::min(t, mesh.triangles.size() - 1)];
  double a = std::fmod(0.7548776662466927 * double(k + 1), 1.0), b = std::fmod(0.5698402909980532 * double(k + 1), 1.0);
  if (a + b > 1.0) a = 1.0 - a, b = 1.0 - b;
  const Vec3f& v0 = mesh.vertices[tri[0]];
  return v0 + float(a) * (mesh.vertices[tri[1]] - v0) + float(b) * (mesh.vertices[tri[2]] - v0);
}

// The distance from s along −n (n outward) to where the ray leaves the shape, sphere-traced from `start` below s,
// and the outward normal where it leaves; depth < 0 when it does not land within the step cap (a ray along a
// surface, or out through an open mesh).
struct Landing {
  float depth = -1.0f;
  Vec3f normal{Vec3f::Zero()};
};
Landing wall_along_normal(const MeshField& field, const Vec3f& s, const Vec3f& n, float start, float far) {
  float depth = start;
  for (int it = 0; it < 64 && depth < far; ++it) {
    const MeshField::Closest c = field.closest(s - depth * n, far);
    if (c.distance < 0.25f * start) return {depth, c.normal};
    depth += c.distance;
  }
  return {};
}

}  // namespace

std::optional<Thickness> measure_thickness(const MeshField& field, const io::TriangleMesh& mesh,
                                           const ThicknessParams& params) {
  if (mesh.triangles.empty() || params.points == 0) return std::nullopt;
  std::vector<double> cumulative(mesh.triangles.size());
  double area = 0.0;
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const auto& tri = mesh.triangles[t];
    const Vec3f& v0 = mesh.vertices[tri[0]];
    area += 0.5 * double((mesh.vertices[tri[1]] - v0).cross(mesh.vertices[tri[2]] - v0).norm());
    cumulative[t] = area;
  }
  if (!(area > 0.0)) return std::nullopt;
  const float diagonal = mesh.bounds().size().norm();
  const float start = 1e-4f * diagonal;  // below the surface: where the ray starts, and the landing tolerance
  const std::size_t n = params.points;
  std::vector<float> wall(n, -1.0f);
  std::vector<Vec3f> at(n);
  core::parallel_for(static_cast<std::int64_t>(n), [&](std::int64_t kk) {
    const auto k = static_cast<std::size_t>(kk);
    const Vec3f p = surface_point(mesh, cumulative, k, n);
    const MeshField::Closest c = field.closest(p);  // the outward normal there (after the field's orientation)
    at[k] = c.point;
    // A wall has a far side facing back; a ray that leaves through a neighbouring face of a wedge (a tetrahedron's
    // edge, a cone's tip) measures how near the edge it started, and counts as no wall (thick).
    const Landing l = wall_along_normal(field, c.point, c.normal, start, diagonal);
    if (l.depth > 0.0f && l.normal.dot(c.normal) <= params.facing_back) wall[k] = l.depth;
  });
  // The quantiles are over every point, those without a wall counting as thick: a shape with thin walls over less
  // than `percentile` of its surface has none worth a spacing.
  std::vector<std::size_t> order(n);
  for (std::size_t k = 0; k < n; ++k) order[k] = k;
  const auto thick = [&](std::size_t k) { return wall[k] > 0.0f ? wall[k] : std::numeric_limits<float>::infinity(); };
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return thick(a) < thick(b) || (thick(a) == thick(b) && a < b); });
  const auto pick = [&](double q) { return order[std::min(n - 1, static_cast<std::size_t>(q * double(n)))]; };
  const std::size_t thin = pick(params.percentile);
  if (!(wall[thin] > 0.0f)) return std::nullopt;
  Thickness th;
  th.thinnest = wall[thin];
  th.where = at[thin];
  th.median = thick(pick(0.5));
  const auto within = std::count_if(order.begin(), order.end(), [&](std::size_t k) { return thick(k) <= 1.5f * th.thinnest; });
  th.thin_area_share = double(within) / double(n);
  return th;
}

}  // namespace ff::sampling
