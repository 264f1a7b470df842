#pragma once
// Uniform-grid neighbour search with compact (CSR) neighbour lists.
//
// Points are binned into cubic cells of edge `radius` by a stable parallel counting sort, so each
// cell's points are one contiguous run of `sorted()`. A neighbour query then scans the 27 cells
// around a point. Dense bounding-box cell keys are used while the box has few cells; a domain that is
// large relative to the particle count falls back to a hashed key space of ~N buckets (collisions are
// harmless: candidates are filtered by distance, and duplicate buckets among the 27 are skipped).
//
// Determinism: lists depend only on the input, never on the thread count: the sort is stable and each
// particle's list is filled by one thread in a fixed cell order (CompactNSearch's brute-force oracle is
// in tests/core/neighbor_grid_test.cpp).
#include "core/types.h"

#include <span>
#include <vector>

namespace ff::core {

/// Neighbour lists in CSR form, stored as one segment per thread chunk so a single pass can fill them
/// without an extra count pass or a copy. Neighbours of i: `of(i)` (self excluded, order deterministic).
struct NeighborList {
  std::size_t count = 0;                   ///< number of query points
  std::size_t chunk = 1;                   ///< query points per segment (the last may be shorter)
  std::vector<std::vector<Index>> index;   ///< per segment: concatenated neighbour indices
  std::vector<std::vector<Index>> offset;  ///< per segment: local offsets, size = points in segment + 1

  std::span<const Index> of(std::size_t i) const {
    const std::size_t s = i / chunk, l = i - s * chunk;
    const auto& off = offset[s];
    return {index[s].data() + off[l], index[s].data() + off[l + 1]};
  }
  std::size_t size() const { return count; }
  /// Total number of (point, neighbour) entries.
  std::size_t total() const;
  /// Bytes held (capacity), for the solver's memory estimate.
  std::size_t bytes() const;
};

class NeighborGrid {
 public:
  /// `radius` (metres, > 0) is both the cell edge and the largest query radius.
  explicit NeighborGrid(float radius) : radius_(radius) {}

  float radius() const { return radius_; }

  /// Bins `points`. Afterwards `sorted()` lists point indices grouped by cell (stable: ascending within a cell).
  void build(std::span<const Vec3f> points);

  /// Point indices in cell order: the permutation that a caller may apply to its arrays for locality
  /// (new[i] = old[sorted()[i]]); then call `points_were_sorted()` so the grid refers to the new order.
  const std::vector<Index>& sorted() const { return sorted_; }
  void points_were_sorted();

  /// For every binned point i: all other binned points j with |x_i − x_j| < radius. `points` must be the
  /// array given to build() (or its sorted copy after points_were_sorted()).
  void neighbors(std::span<const Vec3f> points, NeighborList& out) const;

  /// For every query point q: all binned points j with |q − x_j| < r (r ≤ radius()).
  void query(std::span<const Vec3f> binned, std::span<const Vec3f> queries, float r, NeighborList& out) const;

  bool hashed() const { return hashed_; }
  std::size_t cell_count() const { return cell_start_.empty() ? 0 : cell_start_.size() - 1; }
  std::size_t bytes() const;

 private:
  Vec3i cell_of(const Vec3f& p) const;
  // Fills keys[0..] with the distinct keys of the cells around `c`; returns how many.
  int neighbor_keys(const Vec3i& c, Index* keys) const;
  Index key_of(const Vec3i& c) const;

  template <bool kSelf>
  void gather(std::span<const Vec3f> binned, std::span<const Vec3f> queries, float r, NeighborList& out) const;

  float radius_;
  Vec3f origin_{Vec3f::Zero()};
  Vec3i dims_{Vec3i::Zero()};
  bool hashed_ = false;
  Index hash_mask_ = 0;
  std::vector<Index> sorted_;      // point indices, grouped by cell
  std::vector<Index> cell_start_;  // size cells + 1: run of cell k is sorted_[cell_start_[k] .. cell_start_[k+1])
  std::vector<Index> key_;         // per point: its cell key (scratch kept to avoid reallocation)
  std::vector<Index> key_scratch_; // points_were_sorted(): keys in the new order
  std::vector<Index> histogram_;   // per thread × cell counts (scratch)
};

/// new[i] = old[perm[i]] for one array; `scratch` is reused between calls.
template <class T>
void apply_permutation(std::vector<T>& a, std::span<const Index> perm, std::vector<T>& scratch) {
  scratch.resize(a.size());
  const auto n = static_cast<std::int64_t>(a.size());
#pragma omp parallel for schedule(static)
  for (std::int64_t i = 0; i < n; ++i) scratch[static_cast<std::size_t>(i)] = a[perm[static_cast<std::size_t>(i)]];
  a.swap(scratch);
}

/// inv[perm[i]] = i.
std::vector<Index> inverse_permutation(std::span<const Index> perm);

}  // namespace ff::core
