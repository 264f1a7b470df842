#pragma once
// How well the fluid forms one target, per output frame (METHOD.md §d.2, §d.6, §d.8).
//
//   E_fwd     = mean over controlled fluid particles p of min_i ‖x_p − c_i‖  (are they on the target?)
//   E_bwd     = mean over control samples i of min_p ‖c_i − x_p‖, p over the target's fluid (is it filled?)
//   E         = 100 · (E_fwd + E_bwd) / (2 L)  [%],  L = diagonal of the AABB of the control samples
//   E_fwd_all = E_fwd over every fluid particle of the target (E alone can look good when most fluid never
//               arrived, §a.10), inside and splash fractions, E in particle spacings d = 2r.
//
// Frames. Targets move (keyframes) while their control samples keep their rest-frame positions, so the
// shape is built once in its rest frame and the fluid is mapped into it: rest_from_world is rigid times a
// uniform scale s, and every rest-frame distance times world_scale (= s) is metres in the world. L is taken
// in the rest frame (times s): a rotation would change a world-frame AABB, not the shape's size.
//
// Fluid "of the target" = particles whose target id is the target's. METHOD §d.2 writes E_bwd over all fluid;
// per-target fluid is used here so that, in a multi-target scene, fluid meant for one target does not fill
// another's holes (for a single target the two agree).
#include "core/error.h"
#include "core/types.h"
#include "io/triangle_mesh.h"
#include "core/point_grid.h"
#include "core/point_tree.h"
#include "sampling/mesh_field.h"
#include "sampling/sdf_grid.h"

#include <Eigen/Geometry>

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <mutex>
#include <span>
#include <vector>

namespace ff::metrics {

/// One target's shape, built once: its control samples (rest frame) in a grid of cell d_c and a tree (exact
/// nearest-sample distances, near and far; the tree is built on the first query the grid cannot answer, which a
/// formed frame seldom has), and the signed distance of its rest-frame mesh on a grid.
/// Immutable after build(); queries are thread-safe.
class TargetShape {
 public:
  /// `mesh`: the target mesh with its scene transform applied (rest pose), metres. `controls`: its control
  /// samples in the same frame, sampled at spacing `control_spacing` (d_c, m).
  /// The SDF grid has spacing d_c/2 (coarser when the box would need more than ~64 M nodes, as the sampler
  /// does) and a margin of 3 d_c; surfaces hidden inside the volume are ignored (sampling::ignore_hidden_surfaces).
  /// Errors: Input for no controls, a non-finite control or a mesh MeshField rejects; Param for a bad spacing.
  static Result<TargetShape> build(const io::TriangleMesh& mesh, std::span<const Vec3f> controls,
                                   float control_spacing);

  /// A skinned target's shape at one pose, cheap enough for every measured frame: the samples posed
  /// (`posed_controls`, in the order `bind` was built with) give the grid, tree, box and L, and the signed distance is
  /// the posed mesh's own (`posed_field`: the bind mesh's field moved to the posed vertices, MeshField::moved),
  /// queried exactly (closest triangle, and inside by a ray's crossings when the mesh is closed, else by the winding
  /// number, through its BVH) instead of on a grid. Rebuilding the posed mesh's SDF grid as build() does costs
  /// ~0.5–2 s a frame for the character. `bind` gives d_c and whether the
  /// target is a sheet. Errors: Input for a size mismatch or a non-finite sample.
  static Result<TargetShape> posed(const TargetShape& bind, sampling::MeshField posed_field,
                                   std::span<const Vec3f> posed_controls);

  /// Signed distance to the mesh surface (rest frame, m, negative inside) by trilinear interpolation of the grid; beyond
  /// the grid box (3 d_c from the mesh), the boundary value plus the distance to the box: positive, an upper
  /// bound. NaN for a non-finite point. A posed shape (posed()) answers from its mesh's field, exactly, at any range
  /// (inside surfaces of overlapping parts count there: a point inside the union near one reads a small negative
  /// distance, which changes no inside or splash share).
  /// An open sheet (a mesh that encloses no volume: its samples are one surface layer, and the fluid was sized as one
  /// particle per sample) is measured as the slab one sample spacing thick that its samples stand for: |distance to the
  /// sheet| − d_c/2, so inside and splash mean for it what they mean for a solid. Its grid's own sign says nothing
  /// (a winding number of ±1/2 either side of an open sheet).
  float signed_distance(const Vec3f& rest_point) const;
  /// What measure() counts a point (rest frame) as: inside (signed distance ≤ r) and splash (> 2r), the same answers
  /// as testing signed_distance(p), and what measure() uses for a posed shape, where it is cheaper: MeshField::inside()
  /// alone settles a point inside the mesh, and a point outside needs only the surface within 2r. NaN: neither.
  struct Where {
    bool inside = false, splash = false;
  };
  Where classify(const Vec3f& rest_point, float r) const;
  /// Whether this is a posed shape (posed()).
  bool posed() const { return field_ != nullptr; }
  /// Whether the target is an open sheet (above).
  bool sheet() const { return sheet_; }
  /// Exact Euclidean distance to the closest control sample (rest frame, m), at any range: the samples' grid
  /// when it can prove the answer, else their tree.
  float nearest_sample_distance(const Vec3f& rest_point) const;
  /// L: diagonal of the axis-aligned bounding box of the control samples, m (rest frame).
  float diagonal() const { return diagonal_; }
  /// The axis-aligned bounding box of the control samples (rest frame).
  const Aabb& sample_bounds() const { return box_; }
  float control_spacing() const { return control_spacing_; }
  std::size_t sample_count() const { return sample_count_; }
  /// Bytes held (SDF values, the samples' grid, their tree once a query has built it).
  std::size_t bytes() const;

  /// The control samples in cell order (their grid), for measure().
  const core::PointGrid& control_grid() const { return grid_; }
  /// The SDF grid of a built (not posed) shape.
  const sampling::SdfGrid& sdf() const { return *sdf_; }

 private:
  TargetShape() = default;
  std::shared_ptr<const sampling::SdfGrid> sdf_;         // bind (built) shapes only
  std::shared_ptr<const sampling::MeshField> field_;     // posed shapes only: the posed mesh
  // The samples' tree, built once when first needed (any thread; std::call_once), shared by copies.
  struct LazyTree {
    std::once_flag once;
    std::atomic<bool> built{false};
    core::PointTree tree;
  };
  const core::PointTree& tree() const;
  core::PointGrid grid_;
  std::shared_ptr<LazyTree> tree_;
  std::size_t sample_count_ = 0;
  Aabb box_;
  bool sheet_ = false;
  float diagonal_ = 0.0f;
  float control_spacing_ = 0.0f;
};

/// One target, one frame. Distances in metres (world), fractions in [0, 1].
struct FrameMetrics {
  std::size_t fluid = 0;       ///< fluid particles of the target (target id match, finite position)
  std::size_t controlled = 0;  ///< of those, controlled (flag != 0): N_ctrl (§d.1)
  /// E_fwd over the controlled particles. With none controlled it falls back to E_fwd over all of the
  /// target's fluid (= e_fwd_all): an empty mean would be undefined, and 0 would reward controlling nothing.
  double e_fwd = 0;
  double e_bwd = 0;            ///< E_bwd: mean over control samples of the distance to the nearest fluid particle
  double error_rate = 0;       ///< E = 100 (e_fwd + e_bwd) / (2 L), %
  double e_fwd_all = 0;        ///< E_fwd over all of the target's fluid
  /// Share of the target's fluid whose centre is inside or within r of the surface (signed distance ≤ r).
  /// Why r: a surface-layer particle of a full packing sits with its centre about r from the surface, on
  /// either side depending on how the lattice meets it, and its sphere overlaps the target either way;
  /// a threshold of 0 would also split such a layer at random by the grid's interpolation error.
  double inside_fraction = 0;
  /// Share of the target's fluid farther than 2r outside the surface (METHOD §d.6 splash). Particles with
  /// r < signed distance ≤ 2r are in neither share.
  double splash_fraction = 0;
  double error_spacings = 0;   ///< E in particle spacings: E·L/(100 d) = (e_fwd + e_bwd)/2 / d, d = 2r
};

/// Measures one target in one frame. `positions`: world-space fluid positions; `target_ids`: per particle
/// target id; `controlled`: per particle 0 / non-zero (all three the same length). `particle_radius`: r, m
/// (world). `rest_from_world`: world → rest frame of `shape`, rigid times a uniform scale; `world_scale`:
/// that scale's inverse (world metres per rest-frame metre). Particles with a non-finite position are
/// skipped (the solver reports a blow-up itself).
/// With no fluid of the target, every distance and E are NaN (undefined) and the fractions 0.
/// Cost: O(n + m) for n fluid particles and m samples when the fluid is near the shape (a core::PointGrid over the
/// fluid per call), plus a core::PointTree over the fluid, O(n log n), when some samples have no fluid within
/// about two fluid spacings (holes, fluid not arrived). Deterministic for any thread count (fixed-order
/// sums, exact minima).
FrameMetrics measure(const TargetShape& shape, std::uint8_t target_id, std::span<const Vec3f> positions,
                     std::span<const std::uint8_t> target_ids, std::span<const std::uint8_t> controlled,
                     float particle_radius, const Eigen::Affine3f& rest_from_world = Eigen::Affine3f::Identity(),
                     float world_scale = 1.0f);

}  // namespace ff::metrics
