#pragma once
// For every cell of a coarse grid over the domain, (approximately) the nearest of a set of seed points:
// the gather term (METHOD §a.10) steers unbonded fluid toward the nearest under-filled control sample,
// and a per-particle nearest-neighbour search far from the target would cost (reach/cell)³ cells each.
// Seeds are put in their cells, then two raster sweeps (forward over the 13 causal neighbours, backward
// over the other 13) propagate the closest seed, as in Danielsson's vector distance transform: the
// answer is exact within a cell's size, which is all a steering direction needs.
#include "core/types.h"

#include <array>
#include <span>
#include <vector>

namespace ff::control {

class NearestSeedField {
 public:
  /// A grid over [lo, hi] with cells of edge ≥ `cell` and at most `max_cells` cells.
  void reset(const Vec3f& lo, const Vec3f& hi, float cell, std::size_t max_cells = 1u << 15);
  /// Recomputes the field for `seeds` (indices into `points`). Empty seeds → empty field.
  void compute(std::span<const Vec3f> points, std::span<const Index> seeds);
  /// Index (into `points`) of the seed nearest to p's cell, or kInvalidIndex when there are no seeds.
  Index nearest(const Vec3f& p) const;
  bool empty() const { return empty_; }
  /// The grid reset() chose (the GPU's field, gpu/adaptive_device.h, takes the same cells).
  const Vec3f& lo() const { return lo_; }
  float cell() const { return cell_; }
  const Vec3i& dims() const { return dims_; }

 private:
  Vec3i cell_of(const Vec3f& p) const;
  void sweep(std::span<const Vec3f> points, const std::array<Vec3i, 13>& offsets, bool forward);
  Vec3f lo_{Vec3f::Zero()};
  float cell_ = 1.0f;
  Vec3i dims_{Vec3i::Ones()};
  std::vector<Index> seed_;  // per cell
  std::vector<float> dist2_;
  bool empty_ = true;
};

}  // namespace ff::control
