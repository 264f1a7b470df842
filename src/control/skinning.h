#pragma once
// Skinned targets (issue 19): a target whose mesh file has a skeleton plays one of its clips, and its control
// samples follow the skin. Each sample carries skin weights at the bind pose (sampling/skin_weights.h); every
// sub-step the joints' matrices are evaluated at the clip time and the samples posed by linear blend skinning
// (or dual-quaternion skinning), then by the target's keyframed pose, if any:
//   x(t) = Pose(t) · Σ_j w_j K_j(τ(t)) · x_bind,   K_j = T · G_j(τ) · inverse_bind_j · T⁻¹ (T the scene transform)
// with the clip time τ(t) = speed · (t − start), wrapped into the clip when it loops, held at its ends otherwise.
#include "core/error.h"
#include "core/fields.h"
#include "core/types.h"
#include "io/skin.h"
#include "io/triangle_mesh.h"

#include <Eigen/Geometry>

#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace ff::control {

enum class SkinningMethod { Linear, DualQuaternion };
enum class SkinWeightSource { ClosestPoint, Diffusion };
constexpr std::array<core::Choice<SkinWeightSource>, 2> field_choices(SkinWeightSource) {
  return {{{SkinWeightSource::ClosestPoint, "closest_point"}, {SkinWeightSource::Diffusion, "diffusion"}}};
}
constexpr std::array<core::Choice<SkinningMethod>, 2> field_choices(SkinningMethod) {
  return {{{SkinningMethod::Linear, "linear"}, {SkinningMethod::DualQuaternion, "dual_quaternion"}}};
}

/// A scene target's "animation": which clip of its (skinned) file plays, and how.
struct AnimationSpec {
  std::string clip;      ///< the clip's name or index in the file; empty: the target is not animated (as today)
  double speed = 1.0;    ///< clip seconds per scene second. (0, 100]
  bool loop = true;      ///< wrap around at the clip's end (else hold its last pose)
  double start = 0.0;    ///< s of scene time at which the clip's time 0 plays (before: its first pose). [0, 1e6]
  SkinningMethod skinning = SkinningMethod::Linear;  ///< how the samples are posed: linear blend or dual quaternion
  SkinWeightSource weights = SkinWeightSource::Diffusion;  ///< the samples' weights: closest surface point, or diffused
  bool active() const { return !clip.empty(); }
  template <class S, class F>
  static void fields(S& s, F&& f) {
    using namespace core;
    f("clip", s.clip, plain("the clip's name or index in the mesh file (glTF, FBX, Collada, X ...)"));
    f("speed", s.speed, open_closed(0.0, 100.0, "clip seconds per scene second"));
    f("loop", s.loop, plain("wrap around at the clip's end, else hold its last pose"));
    f("start", s.start, closed(0.0, 1e6, "s of scene time at which the clip starts"));
    f("skinning", s.skinning, plain("how the control samples follow the skin"));
    f("weights", s.weights, plain("the control samples' skin weights: of the closest surface point, or diffused inside"));
  }
};

/// A target's skin as the controllers and the metrics use it: the file's skin, its scene transform and clip.
struct TargetSkin {
  io::Skin skin;
  io::Mat4f transform = io::Mat4f::Identity();  ///< T: the file's scene space → world (the target's transform)
  int clip = -1;         ///< index in skin.clips
  AnimationSpec spec;

  /// τ(t): the clip time at scene time t.
  double clip_time(double t) const;
  /// K_j(τ(t)) per joint, in the world (T · G_j · inverse_bind_j · T⁻¹).
  void world_joint_matrices(double t, std::vector<io::Mat4f>& out) const;
};

/// The joints of one pose, ready to skin points: the matrices K_j, and for dual-quaternion skinning each one's
/// rigid part as a unit dual quaternion and the rest (an animated scale) as a stretch matrix.
class PosedJoints {
 public:
  void set(std::vector<io::Mat4f> K, SkinningMethod method);
  /// The point skinned by its influences (world, bind pose → posed).
  Vec3f apply(const std::array<std::uint16_t, io::kMaxInfluences>& joints,
              const std::array<float, io::kMaxInfluences>& weights, const Vec3f& bind) const;
  const std::vector<io::Mat4f>& matrices() const { return K_; }

 private:
  std::vector<io::Mat4f> K_;
  SkinningMethod method_ = SkinningMethod::Linear;
  std::vector<Eigen::Quaternionf> q0_, qe_;
  std::vector<Eigen::Matrix3f> stretch_;
};


/// An open sheet's samples ride their bind triangles. Sample i sits at barycentrics `bary[i]` of triangle
/// `triangle[i]` of the bind mesh, `height[i]` along that triangle's unit normal (the mesh's winding); posed, it sits
/// at the same barycentrics and height on the posed triangle, whose vertices are skinned by their own weights. So it
/// stays on the posed sheet exactly. A sample skinned by its own (interpolated) weights does not: linear blend
/// skinning of a blend of vertices is not the blend of the skinned vertices, and a coarse sheet bends at its
/// vertices, cutting the corner the samples' smooth blend goes round (glTF2/simple_skin: 96.9 % of the fluid
/// inside against the posed sheet, bench/RESULTS.md "Animated characters, sixth part"). A volume keeps its
/// weight-skinned samples (its interior has no triangle to ride; tried, it cost the fluid more).
struct SurfaceAnchors {
  io::TriangleMesh mesh;  ///< the bind mesh, world (the target's transform applied)
  std::vector<std::array<std::uint16_t, io::kMaxInfluences>> vertex_joints;  ///< per vertex of `mesh`
  std::vector<std::array<float, io::kMaxInfluences>> vertex_weights;
  // Per sample of the target's first sample set.
  std::vector<Index> triangle;
  std::vector<std::array<float, 3>> bary;
  std::vector<float> height;

  /// Whether the arrays agree: one anchor per sample of `samples`, triangles and vertices in range.
  bool consistent(std::size_t samples) const;
  /// The mesh's vertices skinned by `joints` (world, posed; no keyframed pose).
  void pose_vertices(const PosedJoints& joints, std::vector<Vec3f>& out) const;
  /// Sample i on the mesh whose vertices are `posed` (pose_vertices' output, or the bind vertices).
  Vec3f place(std::size_t i, const std::vector<Vec3f>& posed) const;
};

/// Anchors for `samples` (world, bind pose) on `mesh`: each sample's closest triangle (`closest_triangle(i)`, an
/// index into mesh.triangles), its barycentrics there and its height above it. Errors: Param for a triangle out of
/// range or sizes that disagree.
template <class ClosestTriangle>
Result<SurfaceAnchors> anchor_samples(io::TriangleMesh mesh, std::vector<std::array<std::uint16_t, io::kMaxInfluences>> vj,
                                      std::vector<std::array<float, io::kMaxInfluences>> vw,
                                      const std::vector<Vec3f>& samples, ClosestTriangle&& closest_triangle);

// The barycentrics of p's projection into triangle (a, b, c), and its height along the unit normal (b−a)×(c−a)
// (0 for a degenerate triangle: its corner is then taken whole).
void triangle_anchor(const Vec3f& p, const Vec3f& a, const Vec3f& b, const Vec3f& c, std::array<float, 3>& bary,
                     float& height);

template <class ClosestTriangle>
Result<SurfaceAnchors> anchor_samples(io::TriangleMesh mesh, std::vector<std::array<std::uint16_t, io::kMaxInfluences>> vj,
                                      std::vector<std::array<float, io::kMaxInfluences>> vw,
                                      const std::vector<Vec3f>& samples, ClosestTriangle&& closest_triangle) {
  SurfaceAnchors a;
  a.mesh = std::move(mesh), a.vertex_joints = std::move(vj), a.vertex_weights = std::move(vw);
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

}  // namespace ff::control
