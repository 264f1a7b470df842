#include "sampling/weights.h"

#include "core/kernels.h"
#include "core/neighbor_grid.h"
#include "core/parallel.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace ff::sampling {
namespace {

// Calls f(i, neighbours of i within h, self included) for every point. Lists are made in chunks so
// memory stays bounded at wide supports (H_c = 4d holds ~270 samples); points should be in cell order
// so that a chunk's queries share their cells' candidates.
template <class F>
void for_each_neighborhood(std::span<const Vec3f> points, float h, F&& f) {
  core::NeighborGrid grid(h);
  grid.build(points);
  core::NeighborList list;
  constexpr std::size_t kChunk = std::size_t(1) << 15;
  for (std::size_t a = 0; a < points.size(); a += kChunk) {
    const std::size_t b = std::min(points.size(), a + kChunk);
    grid.query(points, points.subspan(a, b - a), h, list);
    core::parallel_for(static_cast<std::int64_t>(b - a), [&](std::int64_t k) {
      f(a + static_cast<std::size_t>(k), list.of(static_cast<std::size_t>(k)));
    });
  }
}

// Puts the samples in cell order (with their depths), so neighbourhood chunks are compact.
void sort_by_cell(ControlSet& set, std::span<float> depth, float h) {
  core::NeighborGrid grid(h);
  grid.build(set.position);
  const auto& perm = grid.sorted();
  std::vector<Vec3f> v3;
  core::apply_permutation(set.position, std::span<const Index>(perm), v3);
  core::apply_permutation(set.velocity, std::span<const Index>(perm), v3);
  std::vector<float> d(depth.begin(), depth.end()), scratch;
  core::apply_permutation(d, std::span<const Index>(perm), scratch);
  std::copy(d.begin(), d.end(), depth.begin());
}

}  // namespace

std::vector<float> kernel_sums(std::span<const Vec3f> points, float h) {
  const core::Poly6 w(h);
  std::vector<float> sums(points.size());
  for_each_neighborhood(points, h, [&](std::size_t i, const core::NeighborRange& nb) {
    double s = 0.0;
    for (Index j : nb) s += w.w_r2((points[i] - points[j]).squaredNorm());
    sums[i] = static_cast<float>(s);
  });
  return sums;
}

double lattice_density(float d, float h, float rest_density) {
  const core::Poly6 w(h);
  double sum = 0.0;
  core::for_each_lattice_point(d, h, [&](int i, int j, int k) { sum += w.w_r2(d * d * float(i * i + j * j + k * k)); });
  return double(rest_density) * double(d) * d * d * sum;
}

Status compute_weights(ControlSet& set, std::span<float> depth, const WeightParams& params) {
  const std::size_t n = set.size();
  if (n == 0) return input_error("compute_weights: the control set is empty");
  if (depth.size() != n) return input_error("compute_weights: one depth per sample is needed");
  if (!(set.spacing > 0.0f)) return input_error("compute_weights: the sampling spacing is not set");
  const float h = params.support_factor * set.spacing;
  set.support = h;
  set.resize(n);
  sort_by_cell(set, depth, h);

  const core::Poly6 w(h);
  const std::vector<float> sums = kernel_sums(set.position, h);
  const auto ni = static_cast<std::int64_t>(n);
  // ω and the weighted centroid (sums in double, in a fixed order).
  core::parallel_for(ni, [&](std::int64_t i) { set.weight[i] = w.w_zero() / sums[i]; });
  const double wsum = core::deterministic_sum(ni, [&](std::int64_t i) { return double(set.weight[i]); });
  Vec3d c = Vec3d::Zero();
  for (int a = 0; a < 3; ++a)
    c[a] = core::deterministic_sum(ni, [&](std::int64_t i) { return double(set.weight[i]) * set.position[i][a]; }) / wsum;
  set.centre = c.cast<float>();
  // φ and its normalisation.
  std::vector<float> phi(n);
  core::parallel_for(ni, [&](std::int64_t i) { phi[i] = (set.position[i] - set.centre).norm(); });
  const auto [lo, hi] = std::minmax_element(phi.begin(), phi.end());
  const float pmin = *lo, pmax = *hi;
  core::parallel_for(ni, [&](std::int64_t i) {
    set.phi[i] = pmax > pmin ? (phi[i] - pmin) / (pmax - pmin) + params.phi_offset : 1.0f;
  });

  // m_c from the interior samples' median kernel sum. A target thinner than 2 H_c has no interior
  // sample: then the best-filled tenth of the samples stands in for it.
  std::vector<float> interior;
  for (std::size_t i = 0; i < n; ++i)
    if (depth[i] >= h) interior.push_back(sums[i]);
  if (interior.size() < 16) {
    interior = sums;
    std::sort(interior.begin(), interior.end());
    interior.erase(interior.begin(), interior.begin() + static_cast<std::ptrdiff_t>(interior.size() * 9 / 10));
  }
  const auto mid = interior.begin() + static_cast<std::ptrdiff_t>(interior.size() / 2);
  std::nth_element(interior.begin(), mid, interior.end());
  const double rho_lattice = lattice_density(set.spacing, h, params.rest_density);
  set.mass = static_cast<float>(rho_lattice / double(*mid));
  core::parallel_for(ni, [&](std::int64_t i) { set.density[i] = set.mass * sums[i]; });
  if (!std::isfinite(set.mass) || !(set.mass > 0.0f))
    return numerical_error(fmt::format("compute_weights: control mass {} is not positive and finite", set.mass));
  return {};
}

}  // namespace ff::sampling
