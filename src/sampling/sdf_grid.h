#pragma once
// The signed distance of a target mesh sampled on a regular grid (docs/ARCHITECTURE.md), so that the
// blue-noise relaxation (30 steps over up to 1M samples) reads distance, outward normal and closest surface
// point by trilinear interpolation in O(1) instead of a BVH query each.
//
// Build. Unsigned distance: exact within kBandCells (4) spacings of the surface, where every triangle is
// rasterised into the nodes near it; farther out, each node takes the nearest of its neighbours' triangles in
// sweeps along the axes, which gives the distance to a real triangle: an upper bound, exact at ~97 % of the far
// nodes of the bunny and < 1 spacing over at the rest (the relaxation needs the band; far nodes need the sign).
// Sign: by the winding number, but not at every node. Cells of stride 8, 4, 2, 1 are visited coarse to fine; a
// cell that holds no surface (one corner is farther from the surface than the cell diagonal) and whose eight
// corner winding numbers agree (all > 0.75 or all < 0.25) gives its sign to all of its nodes; every other cell
// is split and its new corners evaluated. For a closed mesh w is constant in a surface-free cell, so the rule is
// exact; on open meshes w is harmonic there and the 0.25 margin keeps it safe. Only the nodes within ~2 cells of
// the surface, or of the w = 0.5 sheet that spans a hole, are evaluated at the finest level (~10 % of the nodes
// of the bunny at diagonal/256).
// Determinism: every phase is a gather over nodes or cells in a fixed order, so the grid is identical for any
// thread count.
#include "core/error.h"
#include "core/progress.h"
#include "core/types.h"
#include "sampling/mesh_field.h"

#include <cstddef>
#include <vector>

namespace ff::sampling {

/// What SdfGrid::build() did (for logs and the benchmark).
struct SdfGridStats {
  std::size_t nodes = 0;
  std::size_t band_nodes = 0;           ///< nodes within SdfGrid::kBandCells spacings of the surface (exact)
  std::size_t winding_evaluations = 0;  ///< nodes whose sign needed a winding number
  double seconds_distance = 0.0;        ///< wall time of the unsigned-distance pass (band + sweeps)
  double seconds_sign = 0.0;            ///< wall time of the sign pass
};

struct SdfGrid {
  Vec3f origin{Vec3f::Zero()};  ///< position of node (0, 0, 0), m
  float spacing = 0.0f;         ///< distance between neighbouring nodes, m
  Vec3i dims{Vec3i::Zero()};    ///< nodes per axis, each ≥ 2
  std::vector<float> value;     ///< signed distance (m, negative inside) at node (i, j, k): value[index(i, j, k)]

  /// The most nodes a grid may have (4 GiB of values).
  static constexpr std::size_t kMaxNodes = std::size_t{1} << 30;
  /// Node values within this many spacings of the surface are exact; beyond, an upper bound (see above).
  static constexpr float kBandCells = 4.0f;

  /// Samples `field`'s signed distance on the grid covering its bounds grown by `margin` on every side
  /// (centred, ≥ 2 nodes per axis). spacing in (0, ∞) m, margin in [0, ∞) m; keep margin ≥ 2·spacing so that
  /// the boundary nodes are outside. Errors: Param for a bad spacing or margin or more than kMaxNodes nodes;
  /// Cancelled when `progress` asks. Memory: 4 bytes per node; 16 per node at the peak of the build.
  static Result<SdfGrid> build(const MeshField& field, float spacing, float margin,
                               core::Progress& progress = core::null_progress(), SdfGridStats* stats = nullptr);

  /// Distance and its gradient (the derivative of the interpolant: not normalised; zero on a medial ridge).
  struct Sample {
    float distance;
    Vec3f gradient;
  };
  /// Trilinear interpolation of the node values. Outside the grid box: the value at the nearest box point plus
  /// the distance to the box (positive as long as the boundary nodes are). NaN distance for a non-finite p.
  Sample sample(const Vec3f& p) const;
  float distance(const Vec3f& p) const { return sample(p).distance; }
  /// The outward unit normal direction ∇d/|∇d| (zero where the interpolant is flat, e.g. at a medial point).
  Vec3f gradient(const Vec3f& p) const;
  /// The nearby point of the zero level set: Newton steps x ← x − d(x)·∇d/|∇d|² (at most 4, stopping once
  /// |d| ≤ 1e-3·spacing); the first alone is p − d(p)·gradient(p). Within h/2 of the surface near it.
  Vec3f project_to_surface(const Vec3f& p) const;

  std::size_t node_count() const { return value.size(); }
  std::size_t index(int i, int j, int k) const {
    return static_cast<std::size_t>(i) +
           static_cast<std::size_t>(dims.x()) *
               (static_cast<std::size_t>(j) + static_cast<std::size_t>(dims.y()) * static_cast<std::size_t>(k));
  }
  Vec3f node(int i, int j, int k) const { return origin + spacing * Vec3f(float(i), float(j), float(k)); }
  /// Bytes held: 4 per node.
  std::size_t bytes() const { return sizeof(*this) + value.capacity() * sizeof(float); }
};

/// The most nodes an automatically sized grid has (256 MiB of values, ~1 GiB at the peak of its build).
inline constexpr double kAutoSdfNodes = 64e6;

/// The most nodes the sampler's grid has (32 MiB of values). Its grid only guides the relaxation and the spacing
/// repair (every sample is checked against the mesh itself), and above ~250k samples half a spacing made it the
/// slowest stage: the 1M bunny's grid of 32 M nodes took 15.9 of 33.6 s; at 4.3 M nodes (0.98 d) 3.0 of 19.4 s, with
/// the same nearest-neighbour spacings (min 0.85 d, 1st percentile 0.89 d, mean 0.975 d; bench/RESULTS.md).
inline constexpr double kSamplerSdfNodes = 8e6;

/// The spacing of the SDF grids the sampler and the metrics build over a target: half the sample spacing d
/// (0.6 d was measured to lose thin tips: the bunny's ear tips uncovered with 4 of 10 seeds), coarser in steps of
/// 1.25 where `box` grown by `margin` would need more than `max_nodes` nodes.
float auto_sdf_spacing(const Aabb& box, float margin, float d, double max_nodes = kAutoSdfNodes);

/// About the node count SdfGrid::build gives over `box` grown by `margin` at `spacing` (for memory budgets).
double sdf_node_count(const Aabb& box, float spacing, float margin);

}  // namespace ff::sampling
