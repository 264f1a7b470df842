#pragma once
// Keyframed motion of a target (the paper's moving control particles, v_c): a rigid motion with a uniform
// scale about the target's pivot (its rest bounding-box centre), interpolated between keyframes.
//   x_world = pivot + translate + s R (x_rest − pivot),   R = R_z R_y R_x (degrees, as the scene transform)
// Before the first keyframe the target holds the first pose, after the last the last one. Angles and scale
// are interpolated component-wise, linearly or with smoothstep easing (zero speed at every keyframe).
#include "core/error.h"
#include "core/fields.h"
#include "core/types.h"

#include <Eigen/Geometry>

#include <optional>
#include <string_view>
#include <vector>

namespace ff::pose {

struct Keyframe {
  double time = 0.0;               ///< s, ≥ 0, strictly increasing along the list
  Vec3f translate{Vec3f::Zero()};  ///< m, added to the rest position
  Vec3f rotate_deg{Vec3f::Zero()}; ///< degrees about x, y, z through the pivot
  float scale = 1.0f;              ///< uniform, about the pivot; (0, 1e3]
  template <class S, class F>
  static void fields(S& s, F&& f) {
    using namespace core;
    f("time", s.time, required(closed(0.0, 1e6, "s, strictly increasing along the list")));
    f("translate", s.translate, closed(-1e6, 1e6, "m, added to the rest position"));
    f("rotate", s.rotate_deg, closed(-1e6, 1e6, "degrees about x, y, z through the pivot"));
    f("scale", s.scale, open_closed(0.0, 1e3, "uniform, about the pivot"));
  }
};

struct Pose {
  Eigen::Matrix3f rotation = Eigen::Matrix3f::Identity();
  float scale = 1.0f;
  Vec3f translate{Vec3f::Zero()};
  Vec3f pivot{Vec3f::Zero()};
  Vec3f apply(const Vec3f& x) const { return pivot + translate + scale * (rotation * (x - pivot)); }
  /// World → rest frame (rigid times 1/scale), for the metrics.
  Eigen::Affine3f rest_from_world() const;
};

/// The pose of one keyframe's values (rotation R = R_z R_y R_x from degrees), about a pivot set by the caller.
Pose make_pose(const Vec3f& translate, const Vec3f& rotate_deg, float scale);

struct TargetMotion {
  std::vector<Keyframe> keys;
  bool smooth = false;           ///< smoothstep easing between keyframes (else linear)
  Vec3f pivot{Vec3f::Zero()};
  /// A pose set at run time (control/steering.h: the live viewer's drag). When set it replaces the keyframes
  /// from then on; a scene never sets it, so runs from scene files are unchanged.
  std::optional<Pose> live{};

  bool moving() const { return !keys.empty() || live.has_value(); }
  Pose at(double time) const;
  Status validate(std::string_view path) const;
};

}  // namespace ff::pose
