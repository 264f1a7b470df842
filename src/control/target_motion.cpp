#include "control/target_motion.h"

#include "core/params.h"

#include <fmt/format.h>

#include <cmath>
#include <numbers>

namespace ff::control {

namespace {
Eigen::Matrix3f rotation_of(const Vec3f& deg) {
  const float k = static_cast<float>(std::numbers::pi / 180.0);
  return (Eigen::AngleAxisf(deg.z() * k, Vec3f::UnitZ()) * Eigen::AngleAxisf(deg.y() * k, Vec3f::UnitY()) *
          Eigen::AngleAxisf(deg.x() * k, Vec3f::UnitX()))
      .toRotationMatrix();
}
}  // namespace

Eigen::Affine3f Pose::rest_from_world() const {
  // x_rest = pivot + R^T (x − pivot − translate) / s
  Eigen::Affine3f a = Eigen::Affine3f::Identity();
  a.linear() = rotation.transpose() / scale;
  a.translation() = pivot - a.linear() * (pivot + translate);
  return a;
}

Pose make_pose(const Vec3f& translate, const Vec3f& rotate_deg, float scale) {
  Pose p;
  p.translate = translate;
  p.rotation = rotation_of(rotate_deg);
  p.scale = scale;
  return p;
}

Pose TargetMotion::at(double time) const {
  Pose p;
  p.pivot = pivot;
  if (live) {  // steered live: the pose set last, about this target's own pivot
    p = *live;
    p.pivot = pivot;
    return p;
  }
  if (keys.empty()) return p;
  const Keyframe* a = &keys.front();
  const Keyframe* b = a;
  float u = 0.0f;
  if (time >= keys.back().time) {
    a = b = &keys.back();
  } else if (time > keys.front().time) {
    std::size_t k = 1;
    while (keys[k].time <= time) ++k;
    a = &keys[k - 1], b = &keys[k];
    u = static_cast<float>((time - a->time) / (b->time - a->time));
    if (smooth) u = u * u * (3.0f - 2.0f * u);
  }
  p = make_pose(a->translate + u * (b->translate - a->translate), a->rotate_deg + u * (b->rotate_deg - a->rotate_deg),
                a->scale + u * (b->scale - a->scale));
  p.pivot = pivot;
  return p;
}

Status TargetMotion::validate(std::string_view path) const {
  for (std::size_t k = 0; k < keys.size(); ++k) {
    const auto p = fmt::format("{}.keyframes[{}]", path, k);
    FF_CHECK(core::validate_fields(keys[k], p));
    if (k > 0 && !(keys[k].time > keys[k - 1].time))
      return param_error(fmt::format("{}.time = {} must be later than the keyframe before it ({})", p, keys[k].time,
                                     keys[k - 1].time));
  }
  return {};
}

}  // namespace ff::control
