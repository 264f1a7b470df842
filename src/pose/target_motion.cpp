#include "pose/target_motion.h"

#include "core/keys.h"

#include "core/params.h"
#include "core/rotation.h"


#include <cmath>

namespace ff::pose {


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
  p.rotation = core::rotation_from_degrees<float>(rotate_deg);
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
  return core::validate_keys(std::span<const Keyframe>(keys), path, "keyframes", "keyframe");
}

}  // namespace ff::pose
