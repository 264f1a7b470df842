#pragma once
// Cluster-pair lists for the pair kernels (the design of GROMACS' nbnxm, simplified): a point set is binned into
// vertical columns of 2d × 2d (d the particle spacing), sorted by z within each column and cut into clusters of
// kClusterWidth points, so a cluster is a compact ~2d cube; the clusters are stored as padded SoA (x, y, z), and a
// pair list names, for every cluster of one set, the clusters of another set whose bounding boxes come within a
// radius. A kernel then loads a whole j-cluster with three contiguous vector loads and masks the lanes by the
// distance test, where a per-particle neighbour list loads every neighbour from a scattered address.
//
// The list is built on the positions at the start of a sub-step and used by every iteration of it on the moved
// positions x*: the kernels test the distance at x*, so a pair that comes into range during the sub-step is seen
// as long as its clusters were listed (the bounding boxes make a small buffer). Padding lanes hold a point far from
// everything (kFar): its distance test fails, so no kernel needs a lane count.
//
// Determinism: each cluster's list is in ascending j-cluster order and does not depend on the thread count.
#include "core/neighbor_grid.h"  // Buffer
#include "core/types.h"

#include <span>
#include <vector>

namespace ff::core {

inline constexpr std::size_t kClusterWidth = 8;
/// The coordinate of padding lanes: r² ≈ 3e36 to anything real, still finite.
inline constexpr float kFar = 1e18f;

inline std::size_t cluster_count(std::size_t points) { return (points + kClusterWidth - 1) / kClusterWidth; }

/// A point set as clusters: lane l of cluster c is point `point[c·W + l]` (kInvalidIndex for padding); SoA
/// coordinates in that layout, and a bounding box per cluster (of the positions given to assign()). Per-pass values
/// of the kernels live in the same padded layout, so a j-cluster's values are one contiguous load too.
struct ClusterSet {
  std::size_t points = 0, clusters = 0;
  Buffer<Index> point;             // clusters × kClusterWidth
  Buffer<float> x, y, z;           // padding lanes at kFar
  std::vector<Vec3f> lo, hi;       // per cluster: bounding box of its real points

  /// Clusters `p` (columns of 2·spacing, z order within a column, ties by index) and stores it.
  void assign(std::span<const Vec3f> p, float spacing);
  /// Coordinates only, same clusters (the boxes stay those of assign()): the moved positions x* of a sub-step.
  void update(std::span<const Vec3f> p);
  std::size_t padded() const { return clusters * kClusterWidth; }
  std::size_t bytes() const;
};

/// CSR over the clusters of set A: `of(c)` lists the clusters of set B in range of cluster c, ascending.
struct ClusterPairs {
  std::vector<Index> offset;  // size A.clusters + 1
  std::vector<Index> j;
  std::size_t size() const { return offset.empty() ? 0 : offset.size() - 1; }
  std::span<const Index> of(std::size_t c) const { return {j.data() + offset[c], j.data() + offset[c + 1]}; }
  std::size_t total() const { return j.size(); }
  std::size_t bytes() const { return offset.capacity() * sizeof(Index) + j.capacity() * sizeof(Index); }
};

/// Reusable scratch of build_cluster_pairs (a grid of B's cluster centres).
struct ClusterPairScratch {
  std::vector<Index> cell_start, order, cursor;
};

/// For every cluster of `a`: the clusters of `b` whose bounding boxes are closer than `r` (a == b lists a
/// cluster with itself). Every point pair closer than r at the positions of assign() is covered.
void build_cluster_pairs(const ClusterSet& a, const ClusterSet& b, float r, ClusterPairs& out,
                         ClusterPairScratch& scratch);

}  // namespace ff::core
