#pragma once
// A guard that keeps a cage's samples inside the posed mesh (issue 19). Mean value coordinates move the samples
// smoothly with the cage's posed vertices, but linear blend skinning of a coarse mesh folds its bends in (the posed
// surface is the interpolation of a few far-apart vertices, which cuts every bend's corner): huesitos.fbx, a
// 62-vertex cylinder bent through 9 bones, kept only 96.4 % of its caged samples inside its posed mesh at worst, and
// those outside were 0.07 d_c out at the median, 0.55 d_c at most. A sample outside its target pulls fluid out of it.
//
// Which samples, and near which triangles, is found once from the clip: at the bind pose and many of the clip's
// times (kGuardPoses) the mesh is posed and every sample placed in it. A sample that comes within half a spacing of
// the surface (or leaves the mesh) at one of them is guarded; its guard keeps the triangles closest to it at all of
// them and their edge neighbours (not only those it came near: where two limbs come close, a sample deep in one
// passes near the other's surface, and judged by that surface alone at another pose it would seem far out and be
// pulled over to it). Posed, a guarded sample finds the closest point q of those posed triangles and its depth d
// there (signed by the angle-weighted pseudo-normal of q's face, edge or corner, Bærentzen & Aanæs 2005); below its
// guard depth m it is moved along the line through q to the depth
//   φ(d) = m² / (2m − d),   d < m
// which equals d and has slope 1 at d = m (so posing stays smooth), and stays positive however far out it was
// (0.16 d_c for a sample 0.55 d_c out, m = 0.5 d_c). m is the sample's bind depth, within [kMinGuardDepth,
// kGuardBand] spacings, so at the bind pose, of the samples inside the bind mesh, only those closer than
// kMinGuardDepth to the surface move (inward, by less than that). A larger least depth pushes samples on a thin edge
// of the mesh through its other side (0.25 d_c: 1-8 of huesitos' 4017 samples out at clip times where 0.1 d_c keeps
// all in).
//
// Folds. Where the pose folds the mesh over itself (linear blend skinning crushes huesitos' bends so that three of its
// triangles turn inside out at t = 0.39 s), the fold's pocket is outside by the winding number though inside by its
// nearest triangle, and easing along that triangle cannot leave it. So the clip's poses are tried once more with the
// guard: a guarded sample that still ends outside at one of them gets a partner, the nearest sample at least
// kFoldPartnerDepth spacings deep at bind that is inside at every pose. Posed, where one of its triangles is folded
// against a neighbour (normals' cosine below kFoldCosine) and the exact winding number of the posed mesh says it is
// outside, it is moved towards its partner: to the inner end of kFoldSteps halvings of the way between them. That
// move jumps as the sample enters and leaves the pocket, so the sample's velocity u_c leaves it out
// (MeshAnchors::place(…, folds = false)); with it, huesitos took 17 % more sub-steps by the CFL rule (12.22 a frame
// against 10.41).
//
// Measured on huesitos (4017 samples, tests/pipeline/skinned_target_test.cpp), the share inside the posed mesh at five
// clip times: the cage alone 100, 96.43 (folded), 98.45 (folded), 99.98, 99.95 %; eased in 100, 97.78, 99.33, 100,
// 100 %; with the folds' partners 100 % at all five. What it costs is in bench/RESULTS.md ("eighth part").
#include "pose/mesh_anchors.h"
#include "core/error.h"
#include "sampling/mesh_field.h"

#include <span>
#include <vector>

namespace ff::pose {

/// Clip times sampled to find the samples to guard.
inline constexpr int kGuardPoses = 96;
/// A sample that comes within this many spacings of leaving the posed mesh is guarded; also the largest guard depth.
inline constexpr float kGuardBand = 0.5f;
/// The least guard depth, in spacings (a sample nearer the surface at bind moves in, by less than this).
inline constexpr float kMinGuardDepth = 0.1f;
/// A fold's sample is moved towards a partner at least this many spacings deep at bind ...
inline constexpr float kFoldPartnerDepth = 1.0f;
/// ... by this many halvings of the way from its outside end.
inline constexpr int kFoldSteps = 3;
/// Triangles whose normals' cosine is below this are folded against each other.
inline constexpr float kFoldCosine = -0.5f;


/// What guard_cage found, for the log.
struct CageGuardStats {
  std::size_t guarded = 0;    ///< samples guarded
  std::size_t triangles = 0;  ///< guard triangles, summed over the guarded samples
  std::size_t folded = 0;     ///< guarded samples still outside at a pose (in a fold's pocket), given a partner
};

/// Guards `anchors` (caged, its samples' bind positions those the cage reproduces at the bind vertices): `bind` is
/// the field of anchors.mesh (for its outward orientation), `poses` the mesh's vertices at the clip's sampled times
/// (world, the same count and order), `spacing` the samples' d_c. Replaces any guard it had.
/// Errors: Param for anchors that are not a cage or poses that do not match its vertices.
Result<CageGuardStats> guard_cage(MeshAnchors& anchors, const sampling::MeshField& bind,
                                  std::span<const std::vector<Vec3f>> poses, float spacing);

/// Sample i (guarded), placed by the cage at `x` in the mesh whose vertices are `posed`, kept inside it (`folds`
/// false: eased in only, not moved out of a fold's pocket).
Vec3f keep_inside(const MeshAnchors& anchors, std::size_t i, const Vec3f& x, const std::vector<Vec3f>& posed,
                  bool folds = true);

/// The winding number at p of the anchors' mesh with vertices `posed`, each triangle outward by a.orientation (exact:
/// a sum over every triangle; for a guard's few samples in folds).
float posed_winding_number(const MeshAnchors& a, const std::vector<Vec3f>& posed, const Vec3f& p);

/// The point of triangle (a, b, c) closest to p, and which feature it lies on: 0 the face, 1–3 the edges ab, bc, ca,
/// 4–6 the corners a, b, c (Ericson, "Real-Time Collision Detection" §5.1.5; a degenerate triangle: the closest
/// point of its edges as segments).
Vec3f closest_feature(const Vec3f& p, const Vec3f& a, const Vec3f& b, const Vec3f& c, int& feature);

}  // namespace ff::pose
