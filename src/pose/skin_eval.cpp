// A skin's clips evaluated (pose/skin_eval.h): keys interpolated into node matrices, joint matrices, the pingpong
// clip. No Assimp here: the loader is io/skin.cpp.
#include "pose/skin_eval.h"

#include <algorithm>
#include <cmath>

namespace ff::pose {

using io::AnimationClip;
using io::Mat4f;
using io::NodeChannel;
using io::Quatf;
using io::trs;

namespace {

/// The key interval of `t` in `times` (increasing): i and the blend u ∈ [0, 1] between key i and i + 1.
std::pair<std::size_t, float> locate(const std::vector<double>& times, double t) {
  if (times.size() < 2 || t <= times.front()) return {0, 0.0f};
  if (t >= times.back()) return {times.size() - 1, 0.0f};
  const auto it = std::upper_bound(times.begin(), times.end(), t);
  const auto i = static_cast<std::size_t>(it - times.begin()) - 1;
  const double span = times[i + 1] - times[i];
  return {i, span > 0.0 ? static_cast<float>((t - times[i]) / span) : 0.0f};
}

Vec3f lerp_key(const std::vector<double>& times, const std::vector<Vec3f>& values, double t, const Vec3f& rest) {
  if (values.empty()) return rest;
  const auto [i, u] = locate(times, t);
  if (u == 0.0f || i + 1 >= values.size()) return values[std::min(i, values.size() - 1)];
  return (1.0f - u) * values[i] + u * values[i + 1];
}

Quatf slerp_key(const std::vector<double>& times, const std::vector<Quatf>& values, double t, const Quatf& rest) {
  if (values.empty()) return rest;
  const auto [i, u] = locate(times, t);
  if (u == 0.0f || i + 1 >= values.size()) return values[std::min(i, values.size() - 1)];
  return values[i].slerp(u, values[i + 1]);  // Eigen's slerp takes the shorter arc
}

// Keys (times, values) followed by their mirror images about the clip's end; a key at the end is not doubled.
template <class T>
void mirror_keys(std::vector<double>& times, std::vector<T>& values, double duration) {
  if (times.empty() || times.size() != values.size()) return;
  for (std::size_t k = times.size(); k-- > 0;) {
    const double t = 2.0 * duration - times[k];
    if (t <= times.back()) continue;
    times.push_back(t);
    values.push_back(values[k]);
  }
}
}  // namespace

AnimationClip pingpong_clip(const AnimationClip& clip) {
  AnimationClip out = clip;
  out.name = (clip.name.empty() ? std::string("clip") : clip.name) + " pingpong";
  out.duration = 2.0 * clip.duration;
  for (NodeChannel& ch : out.channels) {
    mirror_keys(ch.translation_times, ch.translations, clip.duration);
    mirror_keys(ch.rotation_times, ch.rotations, clip.duration);
    mirror_keys(ch.scale_times, ch.scales, clip.duration);
  }
  return out;
}

void global_matrices(const io::Skin& skin, int clip, double t, std::vector<Mat4f>& out) {
  const auto& nodes = skin.nodes;
  const auto& clips = skin.clips;
  std::vector<Vec3f> tr(nodes.size()), sc(nodes.size());
  std::vector<Quatf> ro(nodes.size());
  for (std::size_t n = 0; n < nodes.size(); ++n) tr[n] = nodes[n].translation, ro[n] = nodes[n].rotation, sc[n] = nodes[n].scale;
  if (clip >= 0 && static_cast<std::size_t>(clip) < clips.size()) {
    const AnimationClip& c = clips[static_cast<std::size_t>(clip)];
    const double at = std::clamp(t, 0.0, c.duration);
    for (const NodeChannel& ch : c.channels) {
      if (ch.node < 0 || static_cast<std::size_t>(ch.node) >= nodes.size()) continue;
      const auto n = static_cast<std::size_t>(ch.node);
      tr[n] = lerp_key(ch.translation_times, ch.translations, at, tr[n]);
      ro[n] = slerp_key(ch.rotation_times, ch.rotations, at, ro[n]);
      sc[n] = lerp_key(ch.scale_times, ch.scales, at, sc[n]);
    }
  }
  out.resize(nodes.size());
  for (std::size_t n = 0; n < nodes.size(); ++n) {
    const Mat4f local = trs(tr[n], ro[n], sc[n]);
    out[n] = nodes[n].parent >= 0 ? Mat4f(out[static_cast<std::size_t>(nodes[n].parent)] * local) : local;
  }
}

void joint_matrices(const io::Skin& skin, int clip, double t, std::vector<Mat4f>& out) {
  std::vector<Mat4f> global;
  global_matrices(skin, clip, t, global);
  const auto& joint_nodes = skin.joint_nodes;
  const auto& inverse_bind = skin.inverse_bind;
  out.resize(joint_nodes.size());
  for (std::size_t j = 0; j < joint_nodes.size(); ++j)
    out[j] = global[static_cast<std::size_t>(joint_nodes[j])] * inverse_bind[j];
}

}  // namespace ff::pose
