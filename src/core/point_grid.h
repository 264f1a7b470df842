#pragma once
// The fast path of exact nearest-point queries: a uniform grid (counting sort by cell, points copied in cell
// order) searched in the block of cells around the query. It answers only when the answer is provably
// exact, i.e. when the nearest point found is no farther than every cell it did not scan and every point it
// left out; otherwise the caller asks a PointTree (point_tree.h), which is exact at any range but slower
// per query and costs a sort to build. Near the target (almost every query of a formed shape) the grid
// answers; splashed particles, holes and fluid that has not arrived go to the tree.
//
// Determinism: the sort is stable and a query returns the minimum of the same float distances as the tree
// and a brute-force loop, so answers never depend on the thread count or on which path answered.
#include "core/types.h"

#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

namespace ff::core {

class PointGrid {
 public:
  PointGrid() = default;
  /// Bins the points that lie in `region` (inclusive) into cubic cells of edge `cell` (m, > 0); the rest are
  /// left out (and make queries near the region's boundary uncertain). The cell grows when the region would
  /// need more than 8 cells per point (a thin or sparse set). Cost O(n + cells).
  PointGrid(std::span<const Vec3f> points, float cell, const Aabb& region);

  /// Squared distance from `q` to the nearest of *all* the points given to the constructor, when the cells
  /// within `rings` of q's cell prove it; NaN when they do not (ask the tree). +inf for no points at all.
  float nearest2(const Vec3f& q, int rings) const;
  /// nearest2 with one ring, then two.
  float nearest2(const Vec3f& q) const;

  /// The binned points in cell order (spatially coherent: queries in this order share their cells).
  std::span<const Vec3f> points() const { return points_; }
  float cell() const { return cell_; }
  std::size_t cell_count() const { return start_.empty() ? 0 : start_.size() - 1; }
  /// True when every point was binned.
  bool complete() const { return left_out_ == 0; }
  std::size_t bytes() const;

 private:
  Vec3f origin_{Vec3f::Zero()};
  Aabb region_;
  float cell_ = 0.0f;
  std::int64_t dims_[3] = {0, 0, 0};
  std::size_t left_out_ = 0;
  std::vector<Index> start_;   // start_[c] .. start_[c + 1]: points of cell c (x fastest)
  std::vector<Vec3f> points_;  // cell order
};

}  // namespace ff::core
