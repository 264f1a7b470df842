#pragma once
// Skinned targets (issue 19): a target whose mesh file has a skeleton plays one of its clips, and its control
// samples follow the skin. Each sample carries skin weights at the bind pose (pose/skin_weights.h); every
// sub-step the joints' matrices are evaluated at the clip time and the samples posed by linear blend skinning
// (or dual-quaternion skinning), then by the target's keyframed pose, if any:
//   x(t) = Pose(t) · Σ_j w_j K_j(τ(t)) · x_bind,   K_j = T · G_j(τ) · inverse_bind_j · T⁻¹ (T the scene transform)
// with the clip time τ(t) = speed · (t − start), wrapped into the clip when it loops (or played back and forth:
// ClipWrap), held at its ends otherwise.
#include "core/error.h"
#include "core/fields.h"
#include "core/types.h"
#include "io/skin.h"

#include <Eigen/Geometry>

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace ff::pose {

enum class SkinningMethod { Linear, DualQuaternion };
enum class SkinWeightSource { ClosestPoint, Diffusion };
/// How the samples follow the posed mesh (pose/mesh_anchors.h): skinned by their own weights, or anchored to the
/// posed mesh's vertices (an open sheet's to its triangles, a closed mesh's in it as a cage). Auto: anchored for a
/// sheet, and for a closed mesh that is coarse (at most kCageMaxVertices vertices, and at least kCageSamplesPerVertex
/// samples per vertex: huesitos.fbx has 62 and 160; X/anim_test.x 422 and 24, the demo character 3382 and 2.6), where
/// its bends cut the corners the samples' own weights go round. The vertex bound bounds the cost: a caged sample
/// is placed from every vertex, every sub-step.
enum class SampleFollow { Auto, Weights, Mesh };
/// How a looped clip starts over. Repeat: back to its first pose, as a game engine loops it. PingPong: it plays
/// backwards to its first pose, then forwards again, so the pose never jumps. Auto: pingpong when the clip's last pose
/// is not its first (its posed mesh ends more than kClipSeamTolerance of its size from where it starts), else repeat.
/// A liquid cannot follow a jump: huesitos.fbx ends 6.5 m from its start (79 % of its 8.3 m size), and repeated, its
/// wrap at 7.8 s threw 84 % of its fluid out of the shape; X/anim_test.x ends 16 % of its size away.
enum class ClipWrap { Auto, Repeat, PingPong };
inline constexpr double kClipSeamTolerance = 0.01;
inline constexpr std::size_t kCageMaxVertices = 128;
inline constexpr double kCageSamplesPerVertex = 64.0;
constexpr std::array<core::Choice<SkinWeightSource>, 2> field_choices(SkinWeightSource) {
  return {{{SkinWeightSource::ClosestPoint, "closest_point"}, {SkinWeightSource::Diffusion, "diffusion"}}};
}
constexpr std::array<core::Choice<SampleFollow>, 3> field_choices(SampleFollow) {
  return {{{SampleFollow::Auto, "auto"}, {SampleFollow::Weights, "weights"}, {SampleFollow::Mesh, "mesh"}}};
}
constexpr std::array<core::Choice<ClipWrap>, 3> field_choices(ClipWrap) {
  return {{{ClipWrap::Auto, "auto"}, {ClipWrap::Repeat, "repeat"}, {ClipWrap::PingPong, "pingpong"}}};
}
constexpr std::array<core::Choice<SkinningMethod>, 2> field_choices(SkinningMethod) {
  return {{{SkinningMethod::Linear, "linear"}, {SkinningMethod::DualQuaternion, "dual_quaternion"}}};
}

/// A scene target's "animation": which clip of its (skinned) file plays, and how.
struct AnimationSpec {
  std::string clip;      ///< the clip's name or index in the file; empty: the target is not animated (as today)
  double speed = 1.0;    ///< clip seconds per scene second. (0, 100]
  bool loop = true;      ///< wrap around at the clip's end (else hold its last pose)
  ClipWrap wrap = ClipWrap::Auto;  ///< how a looped clip starts over: repeat, pingpong, or auto (by its ends)
  double start = 0.0;    ///< s of scene time at which the clip's time 0 plays (before: its first pose). [0, 1e6]
  SkinningMethod skinning = SkinningMethod::Linear;  ///< how the samples are posed: linear blend or dual quaternion
  SkinWeightSource weights = SkinWeightSource::Diffusion;  ///< the samples' weights: closest surface point, or diffused
  SampleFollow follow = SampleFollow::Auto;  ///< the samples skinned by their weights, or anchored to the posed mesh
  bool active() const { return !clip.empty(); }
  template <class S, class F>
  static void fields(S& s, F&& f) {
    using namespace core;
    f("clip", s.clip, plain("the clip's name or index in the mesh file (glTF, FBX, Collada, X ...)"));
    f("speed", s.speed, open_closed(0.0, 100.0, "clip seconds per scene second"));
    f("loop", s.loop, plain("wrap around at the clip's end, else hold its last pose"));
    f("wrap", s.wrap, plain("how a looped clip starts over: repeat, pingpong (backwards), auto (pingpong if its ends differ)"));
    f("start", s.start, closed(0.0, 1e6, "s of scene time at which the clip starts"));
    f("skinning", s.skinning, plain("how the control samples follow the skin"));
    f("weights", s.weights, plain("the control samples' skin weights: of the closest surface point, or diffused inside"));
    f("follow", s.follow, plain("the control samples skinned by their own weights, or anchored to the posed mesh"));
  }
};

/// A target's skin as the controllers and the metrics use it: the file's skin, its scene transform and clip.
struct TargetSkin {
  io::Skin skin;
  io::Mat4f transform = io::Mat4f::Identity();  ///< T: the file's scene space → world (the target's transform)
  int clip = -1;         ///< index in skin.clips
  AnimationSpec spec;
  /// How clip_time loops: spec.wrap resolved when the skin is loaded (auto: by the clip's ends; only for a looped
  /// clip of positive duration). clip_time reads this, not spec.wrap.
  bool pingpong = false;

  /// τ(t): the clip time at scene time t.
  double clip_time(double t) const;
  /// K_j(τ(t)) per joint, in the world (T · G_j · inverse_bind_j · T⁻¹).
  void world_joint_matrices(double t, std::vector<io::Mat4f>& out) const;
  /// K_j(τ) per joint at clip time τ (not scene time), in the world.
  void clip_joint_matrices(double tau, std::vector<io::Mat4f>& out) const;
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

}  // namespace ff::pose
