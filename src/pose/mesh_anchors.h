#pragma once
// Samples that follow the posed mesh itself (issue 19). A skinned target's samples are normally skinned by their own
// weights (pose/skin_weights.h): they follow the bones' smooth blend. The target, though, is the mesh posed by its
// vertices' weights, and linear blend skinning of a blend of vertices is not the blend of the skinned vertices: a
// coarse mesh bends at its few vertices and cuts the corner that the samples' smooth blend goes round, so samples
// leave it (huesitos.fbx, 62 vertices: 86 % of its samples stay inside its posed mesh; glTF2/simple_skin, a
// 10-vertex sheet: its samples 1.03 d_c off it). Anchored to the mesh, each sample is instead placed from the posed
// vertices, every sub-step:
//  - an open sheet's sample rides its bind triangle: at its barycentrics there and its height along the triangle's
//    unit normal (the mesh's winding), on the posed triangle. It stays on the posed sheet exactly.
//  - a closed mesh's sample is the mean value coordinates (Ju, Schaefer & Warren 2005) of the mesh as a cage: one
//    weight per vertex, summing to 1, that reproduce the sample at the bind pose and move it smoothly with the posed
//    vertices, inside where the cage bends (though not provably: a cage folded hard can push some out, and linear
//    blend skinning folds a coarse mesh's bends: huesitos.fbx kept 96.4 % of its samples inside at worst). So a
//    cage can also carry a guard (pose/cage_guard.h) that eases the samples its clip brings out back in.
// A cage costs one weight per sample and vertex, so it is for coarse meshes (AnimationSpec::follow).
#include "pose/skinning.h"
#include "core/error.h"
#include "core/types.h"
#include "io/skin.h"
#include "io/triangle_mesh.h"

#include <array>
#include <cstdint>
#include <vector>

namespace ff::pose {

struct MeshAnchors {
  io::TriangleMesh mesh;  ///< the bind mesh, world (the target's transform applied)
  std::vector<std::array<std::uint16_t, io::kMaxInfluences>> vertex_joints;  ///< per vertex of `mesh`
  std::vector<std::array<float, io::kMaxInfluences>> vertex_weights;
  // Per sample of the target's first sample set, either on a triangle (a sheet) ...
  std::vector<Index> triangle;
  std::vector<std::array<float, 3>> bary;
  std::vector<float> height;
  /// ... or in the cage (a closed mesh): sample i's weights are cage[i·V, (i+1)·V), V the vertex count.
  std::vector<float> cage;
  /// A cage's guard (pose/cage_guard.h; empty: none): the samples that the clip's poses bring near or out of the
  /// posed mesh, each with the triangles it came near (guard_triangle[guard_begin[i], guard_begin[i+1])) and the depth
  /// guard_depth[i] below which it is eased back in; per triangle, whether its winding is outward (+1, −1) and the
  /// triangle across each edge (kInvalidIndex: a border or a non-manifold edge); per vertex, its triangles.
  std::vector<std::uint32_t> guard_begin;
  std::vector<Index> guard_triangle;
  std::vector<float> guard_depth;
  /// Per sample (empty: none): a deep sample that one in a fold's pocket is moved towards (kInvalidIndex: none).
  std::vector<Index> fold_partner;
  std::vector<std::int8_t> orientation;
  std::vector<std::array<Index, 3>> across;
  std::vector<std::uint32_t> corner_begin;
  std::vector<Index> corner_triangle;

  bool caged() const { return !cage.empty(); }
  bool guarded() const { return !guard_begin.empty(); }
  /// Whether the arrays agree: one anchor per sample of `samples`, triangles and vertices in range.
  bool consistent(std::size_t samples) const;
  /// The mesh's vertices skinned by `joints` (world, posed; no keyframed pose).
  void pose_vertices(const PosedJoints& joints, std::vector<Vec3f>& out) const;
  /// Sample i on the mesh whose vertices are `posed` (pose_vertices' output, or the bind vertices); a guarded
  /// sample is then kept inside the posed mesh (pose/cage_guard.h).
  /// `folds` false: without the move out of a fold's pocket (pose/cage_guard.h), for the sample's velocity.
  Vec3f place(std::size_t i, const std::vector<Vec3f>& posed, bool folds = true) const;
};

/// Anchors for `samples` (world, bind pose) on the sheet `mesh`: each sample's closest triangle
/// (`closest_triangle(i)`, an index into mesh.triangles), its barycentrics there and its height above it.
/// Errors: Param for a triangle out of range or weights that do not match the vertices.
template <class ClosestTriangle>
Result<MeshAnchors> anchor_to_triangles(io::TriangleMesh mesh,
                                        std::vector<std::array<std::uint16_t, io::kMaxInfluences>> vertex_joints,
                                        std::vector<std::array<float, io::kMaxInfluences>> vertex_weights,
                                        const std::vector<Vec3f>& samples, ClosestTriangle&& closest_triangle);

/// Anchors for `samples` (world, bind pose) in the closed mesh `mesh` as a cage (mean value coordinates).
/// Errors: Param for weights that do not match the vertices, or more than `max_weights` weights in all (the memory
/// they take: 4 bytes each), naming the knob.
Result<MeshAnchors> anchor_to_cage(io::TriangleMesh mesh,
                                   std::vector<std::array<std::uint16_t, io::kMaxInfluences>> vertex_joints,
                                   std::vector<std::array<float, io::kMaxInfluences>> vertex_weights,
                                   const std::vector<Vec3f>& samples, std::size_t max_weights);

/// Mean value coordinates of `x` in the closed triangle mesh `mesh`: mesh.vertices.size() weights into `out`, summing
/// to 1, with Σ out[v] · vertex[v] = x. A point on a vertex or a triangle gets that vertex's or triangle's own weights.
void mean_value_coordinates(const io::TriangleMesh& mesh, const Vec3f& x, float* out);

/// The barycentrics of p's projection into triangle (a, b, c), and its height along the unit normal (b−a)×(c−a)
/// (a degenerate triangle: the nearest corner whole, no height).
void triangle_anchor(const Vec3f& p, const Vec3f& a, const Vec3f& b, const Vec3f& c, std::array<float, 3>& bary,
                     float& height);

template <class ClosestTriangle>
Result<MeshAnchors> anchor_to_triangles(io::TriangleMesh mesh,
                                        std::vector<std::array<std::uint16_t, io::kMaxInfluences>> vertex_joints,
                                        std::vector<std::array<float, io::kMaxInfluences>> vertex_weights,
                                        const std::vector<Vec3f>& samples, ClosestTriangle&& closest_triangle) {
  MeshAnchors a;
  a.mesh = std::move(mesh), a.vertex_joints = std::move(vertex_joints), a.vertex_weights = std::move(vertex_weights);
  a.triangle.resize(samples.size()), a.bary.resize(samples.size()), a.height.resize(samples.size());
  for (std::size_t i = 0; i < samples.size(); ++i) {
    const Index t = closest_triangle(i);
    if (t >= a.mesh.triangles.size()) return param_error("a control sample has no closest triangle on its sheet");
    const auto& tri = a.mesh.triangles[t];
    a.triangle[i] = t;
    triangle_anchor(samples[i], a.mesh.vertices[tri[0]], a.mesh.vertices[tri[1]], a.mesh.vertices[tri[2]], a.bary[i],
                    a.height[i]);
  }
  if (!a.consistent(samples.size())) return param_error("a sheet's skin weights do not match its vertices");
  return a;
}

}  // namespace ff::pose
