#pragma once
// The rig of a skinned target carried over to the mesh the fluid formed (issue 19, item 3): skin weights per formed
// vertex and the formed mesh moved back to the bind pose, so that io/write_rigged_glb.h can write it with the
// target's skeleton and clips.
//
// How. The formed mesh is the fluid at time t of clip `clip`, in the world. The target is posed there the way the
// samples are (linear blend skinning with the world joint matrices K_w,j = T · K_j(t) · T⁻¹, K from
// Skin::joint_matrices, T the scene's transform), and for each formed vertex p:
//   1. weights: the closest point q on the posed target (sampling::MeshField's BVH over the posed triangles,
//      warm-started from the previous vertex's triangle within blocks of 256 vertices) lies in triangle (a, b, c) at
//      barycentric (λa, λb, λc); the corner weights are interpolated with those λ (equal joints merged), the four
//      largest kept (ties: the lower joint index) and renormalised to sum 1. Closest point rather than, say, a
//      diffusion: the formed surface lies within a few particle spacings of the target's, and the closest point's
//      weights are the target's own at that place (exact on the surface, continuous across triangle edges).
//   2. bind position: x_bind = A⁻¹ · (p − b), with [A | b] = Σ_k w_k · K_w,j_k, the vertex's own blended matrix.
//      Posing x_bind with the vertex's weights at (clip, t) then gives back p exactly (up to float rounding): the
//      rigged mesh plays through the formed shape at the frame it was formed.
//   Singular blends. Where joints far apart in rotation share a vertex (a blend of rotations 170° apart collapses,
//   LBS's "candy wrapper"), A is (near) singular and A⁻¹ would fling the vertex far from the body. The blend counts as
//   singular when |det A| ≤ 1e-2 · Σ_k w_k |det A_k| (for an equal blend of two rotations by θ: cos²(θ/2) ≤ 0.01,
//   θ ≳ 168.5°) or the result is not finite; such a vertex falls back to the dominant joint (largest weight) of the
//   closest corner of its triangle, d: x_bind = q_bind + A_d⁻¹ · (p − q), where q_bind is the same barycentric point
//   on the target's bind mesh, i.e. the bind-pose surface point plus the offset taken back by one rigid joint. It keeps
//   its interpolated weights, so it no longer round-trips exactly: SkinnedSurface::unreached counts these vertices
//   and max_bind_error_m reports the largest round-trip miss |Σ_k w_k K_w,j_k · x_bind − p| over all vertices.
// Formed triangles stay as they are (same vertices, same order).
//
// Determinism: each vertex's result is a pure function of its position (the warm start changes only the speed,
// up to which of two equally close triangles of a shared edge or vertex is returned, where the interpolated weights
// agree), so any thread count gives the same output.
#include "core/error.h"
#include "io/load_mesh.h"
#include "io/skin.h"
#include "io/triangle_mesh.h"

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace ff::pose {

struct SkinnedSurface {
  io::TriangleMesh bind_mesh;  ///< the formed mesh moved to the bind pose, world space (T applied); same triangles
  std::vector<std::array<std::uint16_t, io::kMaxInfluences>> joints;  ///< per vertex of bind_mesh
  std::vector<std::array<float, io::kMaxInfluences>> weights;         ///< per vertex, sum 1
  std::size_t unreached = 0;      ///< vertices whose own blend was singular (the dominant-joint fallback above)
  double max_bind_error_m = 0;    ///< max over vertices of |pose(x_bind) − p| at (clip, t), m
  double max_distance_m = 0;      ///< the farthest formed vertex from the posed target, m (splashes show here)
};

/// Transfers `skin` (the target's, for `target_bind`) onto `formed`. `formed`: the reconstructed mesh at time `t` (s)
/// of clip `clip` (−1: the rest pose), in the world. `target_bind`: the target's bind-pose mesh in the world, i.e.
/// load_mesh's mesh with the scene transform `transform` applied (the mesh load_skin was given). Errors (Input, one
/// line): an empty formed mesh or target, a non-finite formed vertex, skin weights that do not match the target's
/// vertices, a joint index out of range, a posed target without area (from MeshField::build).
/// Cost: O(n log n) to index the posed target's n triangles, then O(log n) per formed vertex (OpenMP).
Result<SkinnedSurface> transfer_skin(const io::TriangleMesh& formed, const io::TriangleMesh& target_bind,
                                     const io::Skin& skin, const io::MeshTransform& transform, int clip, double t);

/// The world joint matrices T · K_j · T⁻¹ of `skin` at (clip, t) (Skin::joint_matrices conjugated by the scene
/// transform, computed in double): what poses a world-space bind mesh (io::skin_point) as a player of the rigged GLB
/// shows it.
std::vector<io::Mat4f> world_joint_matrices(const io::Skin& skin, const io::MeshTransform& transform, int clip, double t);

}  // namespace ff::pose
