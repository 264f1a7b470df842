#include "sampling/thickness.h"

#include "core/parallel.h"
#include "sampling/samplers.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace ff::sampling {
namespace {

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
  // Points spread over the surface by area, the same on every run (the samplers' generator, a fixed seed).
  const std::vector<Vec3f> points = random_surface_points(mesh, params.points, 0x7417C4E55ull);
  if (points.empty()) return std::nullopt;  // no triangles, or no area
  const float diagonal = mesh.bounds().size().norm();
  const float start = 1e-4f * diagonal;  // below the surface: where the ray starts, and the landing tolerance
  const std::size_t n = points.size();
  std::vector<float> wall(n, -1.0f);
  std::vector<Vec3f> at(n);
  core::parallel_for(static_cast<std::int64_t>(n), [&](std::int64_t kk) {
    const auto k = static_cast<std::size_t>(kk);
    const MeshField::Closest c = field.closest(points[k]);  // the outward normal there (after the field's orientation)
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
