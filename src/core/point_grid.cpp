#include "core/point_grid.h"

#include <algorithm>
#include <cassert>
#include <cmath>

namespace ff::core {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
// The proof compares float distances computed two ways (cell coordinates vs. point differences): shrink the
// bound by far more than their rounding, so that a point it excludes is really no nearer.
constexpr float kBoundSafety = 1.0f - 1e-3f;

}  // namespace

PointGrid::PointGrid(std::span<const Vec3f> points, float cell, const Aabb& region) {
  assert(cell > 0.0f && std::isfinite(cell));
  const std::size_t n = points.size();
  region_ = region;
  if (n == 0) return;
  if (region.empty()) {
    left_out_ = n;
    return;
  }
  origin_ = region.min;
  const Vec3f size = region.size();
  auto cells = [&](float c) {
    double total = 1.0;
    for (int a = 0; a < 3; ++a) total *= std::floor(double(size[a]) / c) + 1.0;
    return total;
  };
  const double max_cells = 8.0 * double(n) + 4096.0;
  while (cells(cell) > max_cells) cell *= 1.25f;
  cell_ = cell;
  for (int a = 0; a < 3; ++a) dims_[a] = static_cast<std::int64_t>(std::floor(size[a] / cell)) + 1;
  const auto cell_total = static_cast<std::size_t>(dims_[0] * dims_[1] * dims_[2]);

  // Counting sort by cell (stable): key, count, prefix sum, scatter.
  std::vector<Index> key(n, kInvalidIndex);
  for (std::size_t i = 0; i < n; ++i) {
    if (!region.contains(points[i])) continue;  // also drops NaN
    std::int64_t c[3];
    for (int a = 0; a < 3; ++a)
      c[a] = std::min(static_cast<std::int64_t>((points[i][a] - origin_[a]) / cell), dims_[a] - 1);
    key[i] = static_cast<Index>(c[0] + dims_[0] * (c[1] + dims_[1] * c[2]));
  }
  start_.assign(cell_total + 1, 0);
  for (Index k : key)
    if (k != kInvalidIndex) ++start_[k + 1];
  for (std::size_t c = 0; c < cell_total; ++c) start_[c + 1] += start_[c];
  points_.resize(start_[cell_total]);
  left_out_ = n - points_.size();
  std::vector<Index> cursor(start_.begin(), start_.end() - 1);
  for (std::size_t i = 0; i < n; ++i)
    if (key[i] != kInvalidIndex) points_[cursor[key[i]]++] = points[i];
}

float PointGrid::nearest2(const Vec3f& q, int rings) const {
  if (points_.empty() && left_out_ == 0) return kInf;  // no points at all
  if (points_.empty()) return kNaN;
  const Vec3f g = (q - origin_) / cell_;
  if (!g.allFinite()) return kNaN;
  // q's cell (clamped far away so that the conversion cannot overflow; such a block holds no cell anyway).
  std::int64_t qc[3], lo[3], hi[3];
  for (int a = 0; a < 3; ++a) {
    qc[a] = static_cast<std::int64_t>(std::floor(std::clamp(g[a], -1e9f, 1e9f)));
    lo[a] = std::max<std::int64_t>(qc[a] - rings, 0);
    hi[a] = std::min<std::int64_t>(qc[a] + rings, dims_[a] - 1);
    if (lo[a] > hi[a]) return kNaN;  // the block misses the grid
  }
  // Each (y, z) row of the block is one contiguous run of the cell-ordered points.
  float best = kInf;
  for (std::int64_t z = lo[2]; z <= hi[2]; ++z)
    for (std::int64_t y = lo[1]; y <= hi[1]; ++y) {
      const auto row = static_cast<std::size_t>(dims_[0] * (y + dims_[1] * z));
      const Index end = start_[row + static_cast<std::size_t>(hi[0]) + 1];
      for (Index k = start_[row + static_cast<std::size_t>(lo[0])]; k < end; ++k)
        best = std::min(best, (points_[k] - q).squaredNorm());
    }
  // Every unscanned cell lies beyond the block's faces; every left-out point beyond the region's.
  float bound = kInf;
  for (int a = 0; a < 3; ++a) {
    const float below = g[a] - float(qc[a] - rings), above = float(qc[a] + rings + 1) - g[a];
    bound = std::min(bound, std::min(below, above) * cell_);
    if (left_out_ > 0)
      bound = std::min(bound, std::max(0.0f, std::min(q[a] - region_.min[a], region_.max[a] - q[a])));
  }
  bound *= kBoundSafety;
  return best <= bound * bound ? best : kNaN;
}

float PointGrid::nearest2(const Vec3f& q) const {
  const float near = nearest2(q, 1);
  return std::isnan(near) ? nearest2(q, 2) : near;
}

std::size_t PointGrid::bytes() const {
  return sizeof(*this) + start_.capacity() * sizeof(Index) + points_.capacity() * sizeof(Vec3f);
}

}  // namespace ff::core
