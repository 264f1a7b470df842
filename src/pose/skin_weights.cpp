#include "pose/skin_weights.h"

#include "core/neighbor_grid.h"
#include "core/parallel.h"

#include <fmt/format.h>

#include <algorithm>
#include <numeric>

namespace ff::pose {

void top_influences(std::span<const float> dense, std::array<std::uint16_t, io::kMaxInfluences>& joints,
                    std::array<float, io::kMaxInfluences>& weights) {
  joints.fill(0);
  weights.fill(0.0f);
  // Insertion into the (sorted) four best: heavier first, the lower joint first among equals.
  std::array<float, io::kMaxInfluences> bw{};
  std::array<std::uint16_t, io::kMaxInfluences> bj{};
  int n = 0;
  for (std::size_t j = 0; j < dense.size(); ++j) {
    const float w = dense[j];
    if (!(w > 0.0f)) continue;
    int k = n < io::kMaxInfluences ? n : io::kMaxInfluences - 1;
    if (n == io::kMaxInfluences && !(w > bw[k])) continue;
    while (k > 0 && w > bw[k - 1]) {
      bw[k] = bw[k - 1], bj[k] = bj[k - 1];
      --k;
    }
    bw[k] = w, bj[k] = static_cast<std::uint16_t>(j);
    n = std::min(n + 1, io::kMaxInfluences);
  }
  float sum = 0.0f;
  for (int k = 0; k < n; ++k) sum += bw[k];
  for (int k = 0; k < n; ++k) joints[k] = bj[k], weights[k] = bw[k] / sum;
}

namespace {

// Each sample's weights (row i of the n × J `dense`) interpolated at its closest point on the mesh, and its distance
// to that point.
void closest_point_weights(const io::TriangleMesh& mesh, const sampling::MeshField& field, const io::Skin& skin,
                           std::span<const Vec3f> samples, std::size_t J, std::vector<float>& dense,
                           std::vector<float>& distance) {
  core::parallel_for(static_cast<std::int64_t>(samples.size()), [&](std::int64_t ii) {
    const auto i = static_cast<std::size_t>(ii);
    const sampling::MeshField::Closest c = field.closest(samples[i]);
    distance[i] = c.distance;
    const auto& tri = mesh.triangles[c.triangle];
    const Vec3f a = mesh.vertices[tri[0]], b = mesh.vertices[tri[1]], cc = mesh.vertices[tri[2]];
    // Barycentric coordinates of the closest point (clamped: it lies on the triangle up to rounding).
    const Vec3f v0 = b - a, v1 = cc - a, v2 = c.point - a;
    const double d00 = v0.dot(v0), d01 = v0.dot(v1), d11 = v1.dot(v1), d20 = v2.dot(v0), d21 = v2.dot(v1);
    const double den = d00 * d11 - d01 * d01;
    double u = 1.0 / 3.0, v = 1.0 / 3.0;
    if (den > 0.0) v = (d11 * d20 - d01 * d21) / den, u = (d00 * d21 - d01 * d20) / den;
    v = std::clamp(v, 0.0, 1.0), u = std::clamp(u, 0.0, 1.0 - v);
    const std::array<double, 3> bary{1.0 - u - v, v, u};
    float* row = dense.data() + i * J;
    for (int k = 0; k < 3; ++k)
      for (int m = 0; m < io::kMaxInfluences; ++m)
        if (skin.weights[tri[k]][m] > 0.0f) row[skin.joints[tri[k]][m]] += float(bary[k]) * skin.weights[tri[k]][m];
  });
}

// Samples within a spacing of the surface keep their closest-point weights; the others relax to the mean of their
// neighbours within 2 d_c (Jacobi iterations; each spreads information by ~1.5 d_c, so the count follows the
// target's size in spacings). Only the joints some sample uses take part (a character's hands do not diffuse into
// its feet's columns).
void diffuse_weights(std::span<const Vec3f> samples, float spacing, std::size_t J, const std::vector<float>& distance,
                     std::vector<float>& dense) {
  const std::size_t n = samples.size();
  std::vector<std::uint32_t> used;
  for (std::size_t q = 0; q < J; ++q)
    for (std::size_t i = 0; i < n; ++i)
      if (dense[i * J + q] > 0.0f) {
        used.push_back(static_cast<std::uint32_t>(q));
        break;
      }
  const std::size_t U = used.size();
  std::vector<float> cur(n * U), next(n * U);
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t q = 0; q < U; ++q) cur[i * U + q] = dense[i * J + used[q]];
  next = cur;
  const float r = 2.0f * spacing;
  core::NeighborGrid grid(r);
  grid.build(samples);
  core::NeighborList near;
  grid.query(samples, samples, r, near);
  Aabb box;
  for (const Vec3f& p : samples) box.extend(p);
  const int iterations = std::clamp(static_cast<int>(box.size().maxCoeff() / spacing), 20, 400);
  for (int it = 0; it < iterations; ++it) {
    core::parallel_for(static_cast<std::int64_t>(n), [&](std::int64_t ii) {
      const auto i = static_cast<std::size_t>(ii);
      if (distance[i] <= spacing) return;
      float* out = next.data() + i * U;
      std::fill(out, out + U, 0.0f);
      std::size_t count = 0;
      for (const Index j : near.of(i)) {
        const float* in = cur.data() + std::size_t(j) * U;
        for (std::size_t q = 0; q < U; ++q) out[q] += in[q];
        ++count;
      }
      if (count == 0) {
        std::copy(cur.data() + i * U, cur.data() + (i + 1) * U, out);
        return;
      }
      for (std::size_t q = 0; q < U; ++q) out[q] /= float(count);
    });
    cur.swap(next);
  }
  std::fill(dense.begin(), dense.end(), 0.0f);
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t q = 0; q < U; ++q) dense[i * J + used[q]] = cur[i * U + q];
}

}  // namespace

Result<SampleSkin> sample_skin_weights(const io::TriangleMesh& mesh, const sampling::MeshField& field, const io::Skin& skin,
                                       std::span<const Vec3f> samples, float spacing, SkinWeighting how) {
  if (skin.joints.size() != mesh.vertices.size() || skin.weights.size() != mesh.vertices.size())
    return param_error(fmt::format("skin weights: {} weighted vertices for a mesh of {}", skin.joints.size(),
                                   mesh.vertices.size()));
  if (!(spacing > 0.0f)) return param_error(fmt::format("skin weights: spacing {} must be > 0", spacing));
  const std::size_t J = skin.joint_nodes.size(), n = samples.size();
  // Dense per-sample weights (n × J): characters have tens of joints and ~10⁴ samples.
  std::vector<float> dense(n * J, 0.0f);
  std::vector<float> distance(n, 0.0f);
  closest_point_weights(mesh, field, skin, samples, J, dense, distance);
  if (how == SkinWeighting::Diffusion && n > 1) diffuse_weights(samples, spacing, J, distance, dense);

  SampleSkin out;
  out.joints.resize(n);
  out.weights.resize(n);
  for (std::size_t i = 0; i < n; ++i) top_influences({dense.data() + i * J, J}, out.joints[i], out.weights[i]);
  return out;
}

}  // namespace ff::pose
