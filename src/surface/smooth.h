#pragma once
// The paper's weighted vertex smoothing (§5.1 eq. 20–21, as corrected in METHOD.md §a.7 / §a.8 item 22):
//   V_i' = V_i + β ΔV_i,   ΔV_i = Σ_{j ∈ N1(i)} w_ij V_j / Σ_j w_ij − V_i,   w_ij = W_poly6(‖V_i − V_j‖, H_v),
// i.e. each vertex moves a fraction β towards the kernel-weighted mean of its 1-ring. All vertices move at
// once per pass (Jacobi), so the result does not depend on vertex order or thread count, and the connectivity
// never changes. Like any Laplacian step it shrinks the surface, most at thin tips: on a lattice-filled bunny
// two passes moved the farthest part of the target 0.12 d farther from the mesh. With `inflate` = μ > 0 each
// pass is followed by the same step with −μ (Taubin's λ|μ smoothing, METHOD.md §a.7: "a safe drop-in if
// shrinkage matters"), which removes the same noise without the shrinkage.
#include "io/triangle_mesh.h"

namespace ff::surface {

struct SmoothParams {
  int passes = 2;        ///< [0, 100]
  float beta = 0.5f;     ///< β ∈ [0, 1]
  float radius = 0.0f;   ///< H_v, m (> 0); neighbours at H_v or farther have weight 0
  float inflate = 0.0f;  ///< μ of the Taubin back-step (0: the paper's plain eq. 20); use μ slightly above β
};

/// Smooths `mesh` in place. A vertex whose neighbours all lie at H_v or farther keeps its place (no weight); the
/// corners of a triangle that smoothing would turn over (normal turned by more than 90°) keep their place too.
void smooth_weighted(io::TriangleMesh& mesh, const SmoothParams& params);

}  // namespace ff::surface
