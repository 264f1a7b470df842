#pragma once
// A hand-built skinned target for the rig tests (issue 19): a closed cylinder ("bar") along +y in the file's scene
// space, a three-node hierarchy (a non-joint "Armature" node offset in x, a "root" joint at the bottom, a "mid" joint
// at half height), weights that blend from root to mid over y ∈ [0.4, 0.6] of a 1 m bar, and two clips:
//   "bend" (1 s): root slides 0.2 m in x, mid turns 0° → 45° → 90° about z (keys at 0, 0.5, 1 s) and grows 1 → 1.1;
//   "wave" (2 s): mid turns about x, 0° → 30° → −30° (keys at 0, 1, 2 s).
// Everything is computed from the definitions here, nothing is read from a file.
#include "io/load_mesh.h"
#include "pose/skin_eval.h"
#include "io/skin.h"
#include "io/triangle_mesh.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

namespace ff::test {

inline constexpr float kBarHeight = 1.0f, kBarRadius = 0.1f, kBarX = 0.05f;

/// A closed cylinder of `radius` along y from 0 to `height`, axis at x = kBarX, z = 0: `rings` + 1 rings of `segments`
/// vertices and a centre vertex per cap; outward CCW triangles.
inline io::TriangleMesh bar_mesh(int rings, int segments, float radius = kBarRadius, float height = kBarHeight) {
  io::TriangleMesh m;
  for (int k = 0; k <= rings; ++k)
    for (int s = 0; s < segments; ++s) {
      const double a = 2.0 * std::numbers::pi * s / segments;
      m.vertices.push_back(Vec3f(kBarX + radius * float(std::cos(a)), height * float(k) / float(rings), radius * float(std::sin(a))));
    }
  const auto at = [&](int k, int s) { return static_cast<Index>(k * segments + (s % segments)); };
  for (int k = 0; k < rings; ++k)
    for (int s = 0; s < segments; ++s) {
      m.triangles.push_back({at(k, s), at(k + 1, s), at(k + 1, s + 1)});
      m.triangles.push_back({at(k, s), at(k + 1, s + 1), at(k, s + 1)});
    }
  const auto bottom = static_cast<Index>(m.vertices.size());
  m.vertices.push_back(Vec3f(kBarX, 0.0f, 0.0f));
  const auto top = static_cast<Index>(m.vertices.size());
  m.vertices.push_back(Vec3f(kBarX, height, 0.0f));
  for (int s = 0; s < segments; ++s) {
    m.triangles.push_back({bottom, at(0, s), at(0, s + 1)});
    m.triangles.push_back({top, at(rings, s + 1), at(rings, s)});
  }
  return m;
}

/// The weight of joint 1 ("mid") at bind height y (file scene space): 0 below 0.4, 1 above 0.6, linear between.
inline float bar_mid_weight(float y) { return std::clamp((y - 0.4f) / 0.2f, 0.0f, 1.0f); }

inline void bar_influence(float y, std::array<std::uint16_t, io::kMaxInfluences>& j, std::array<float, io::kMaxInfluences>& w) {
  const float m = bar_mid_weight(y);
  j = {0, 0, 0, 0};
  w = {0, 0, 0, 0};
  if (m <= 0.0f) j[0] = 0, w[0] = 1.0f;
  else if (m >= 1.0f) j[0] = 1, w[0] = 1.0f;
  else j = {0, 1, 0, 0}, w = {1.0f - m, m, 0.0f, 0.0f};
}

inline io::Quatf about(const Vec3f& axis, double deg) {
  return io::Quatf(Eigen::AngleAxisf(static_cast<float>(deg * std::numbers::pi / 180.0), axis.normalized()));
}

/// The bar's skeleton and clips (no weights: bar_skin adds them for a mesh).
inline io::Skin bar_skeleton() {
  io::Skin s;
  s.nodes.resize(3);
  s.nodes[0].name = "Armature";
  s.nodes[0].translation = Vec3f(kBarX, 0.0f, 0.0f);
  s.nodes[1].name = "root";
  s.nodes[1].parent = 0;
  s.nodes[2].name = "mid";
  s.nodes[2].parent = 1;
  s.nodes[2].translation = Vec3f(0.0f, 0.5f * kBarHeight, 0.0f);
  s.joint_nodes = {1, 2};
  std::vector<io::Mat4f> rest;
  pose::global_matrices(s, -1, 0.0, rest);
  for (int n : s.joint_nodes) s.inverse_bind.push_back(rest[static_cast<std::size_t>(n)].inverse());

  io::AnimationClip bend;
  bend.name = "bend";
  bend.duration = 1.0;
  io::NodeChannel root;
  root.node = 1;
  root.translation_times = {0.0, 1.0};
  root.translations = {Vec3f::Zero(), Vec3f(0.2f, 0.0f, 0.0f)};
  io::NodeChannel mid;
  mid.node = 2;
  mid.rotation_times = {0.0, 0.5, 1.0};
  mid.rotations = {about(Vec3f::UnitZ(), 0), about(Vec3f::UnitZ(), 45), about(Vec3f::UnitZ(), 90)};
  mid.scale_times = {0.0, 1.0};
  mid.scales = {Vec3f::Ones(), Vec3f::Constant(1.1f)};
  bend.channels = {root, mid};
  io::AnimationClip wave;
  wave.name = "wave";
  wave.duration = 2.0;
  io::NodeChannel w;
  w.node = 2;
  w.rotation_times = {0.0, 1.0, 2.0};
  w.rotations = {about(Vec3f::UnitX(), 0), about(Vec3f::UnitX(), 30), about(Vec3f::UnitX(), -30)};
  wave.channels = {w};
  s.clips = {bend, wave};
  return s;
}

/// The skeleton with per-vertex weights for `scene_mesh` (file scene space: weights follow each vertex's height).
inline io::Skin bar_skin(const io::TriangleMesh& scene_mesh) {
  io::Skin s = bar_skeleton();
  s.joints.resize(scene_mesh.vertices.size());
  s.weights.resize(scene_mesh.vertices.size());
  for (std::size_t v = 0; v < scene_mesh.vertices.size(); ++v) bar_influence(scene_mesh.vertices[v].y(), s.joints[v], s.weights[v]);
  return s;
}

/// The scene transforms the rig tests run under: identity; scale 0.1 with a rotation and a translation; a mirror.
inline std::vector<io::MeshTransform> rig_transforms() {
  io::MeshTransform small;
  small.scale = Vec3f::Constant(0.1f);
  small.rotate_deg = Vec3f(20.0f, 35.0f, -10.0f);
  small.translate = Vec3f(0.3f, -0.2f, 0.5f);
  io::MeshTransform mirror;
  mirror.scale = Vec3f(-1.0f, 1.0f, 1.0f);
  mirror.rotate_deg = Vec3f(0.0f, 30.0f, 0.0f);
  mirror.translate = Vec3f(0.0f, 0.1f, 0.0f);
  return {io::MeshTransform{}, small, mirror};
}

/// World positions of `world_bind` skinned with `skin` at (clip, t) under `transform`: LBS with T · K_j · T⁻¹
/// (in double), the pose a rigged GLB player must show.
inline std::vector<Vec3f> pose_world(const io::TriangleMesh& world_bind,
                                     const std::vector<std::array<std::uint16_t, io::kMaxInfluences>>& joints,
                                     const std::vector<std::array<float, io::kMaxInfluences>>& weights, const io::Skin& skin,
                                     const io::MeshTransform& transform, int clip, double t) {
  std::vector<io::Mat4f> k;
  pose::joint_matrices(skin, clip, t, k);
  const Eigen::Matrix4d tm = io::transform_matrix(transform).cast<double>();
  for (auto& m : k) m = (tm * m.cast<double>() * tm.inverse()).cast<float>();
  std::vector<Vec3f> out(world_bind.vertices.size());
  for (std::size_t v = 0; v < out.size(); ++v) out[v] = io::skin_point(k, joints[v], weights[v], world_bind.vertices[v]);
  return out;
}

inline Aabb bounds_of(const std::vector<Vec3f>& p) {
  Aabb b;
  for (const auto& x : p) b.extend(x);
  return b;
}

}  // namespace ff::test
