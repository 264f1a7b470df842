// Keyframed target motion (pose/target_motion.h): poses at, before, after and between keyframes, smoothstep
// easing, the inverse used by the metrics, live poses, and the keyframe checks.
#include "pose/target_motion.h"

#include <gtest/gtest.h>

#include <cmath>

namespace ff::pose {
namespace {

constexpr float kTol = 1e-5f;

TargetMotion two_keys(bool smooth) {
  TargetMotion m;
  m.pivot = Vec3f(1, 0, 0);
  Keyframe a, b;
  a.time = 1.0;
  b.time = 3.0;
  b.translate = Vec3f(2, 0, -4);
  b.rotate_deg = Vec3f(0, 90, 0);
  b.scale = 3.0f;
  m.keys = {a, b};
  m.smooth = smooth;
  return m;
}

TEST(TargetMotion, HoldsTheFirstPoseBeforeAndTheLastAfter) {
  const TargetMotion m = two_keys(false);
  const Vec3f x(2, 1, 0);
  for (double t : {0.0, 0.5, 1.0}) EXPECT_TRUE(m.at(t).apply(x).isApprox(x, kTol)) << t;
  // Last: about the pivot (1, 0, 0), R_y(90°) maps (1, 1, 0) to (0, 1, −1), ×3, + (2, 0, −4).
  const Vec3f last = Vec3f(1, 0, 0) + Vec3f(2, 0, -4) + 3.0f * Vec3f(0, 1, -1);
  for (double t : {3.0, 4.0, 100.0}) EXPECT_TRUE(m.at(t).apply(x).isApprox(last, kTol)) << t << ": " << m.at(t).apply(x).transpose();
  EXPECT_TRUE(m.moving());
  EXPECT_FALSE(TargetMotion{}.moving());
  EXPECT_TRUE(TargetMotion{}.at(5.0).apply(x).isApprox(x));
}

TEST(TargetMotion, InterpolatesLinearlyOrWithSmoothstep) {
  const TargetMotion lin = two_keys(false), smooth = two_keys(true);
  // Halfway both agree (smoothstep(½) = ½): translate (1, 0, −2), 45° about y, scale 2; the pivot stays fixed.
  for (const TargetMotion* m : {&lin, &smooth}) {
    const Pose p = m->at(2.0);
    EXPECT_TRUE(p.translate.isApprox(Vec3f(1, 0, -2), kTol));
    EXPECT_NEAR(p.scale, 2.0f, kTol);
    EXPECT_TRUE(p.apply(m->pivot).isApprox(m->pivot + p.translate, kTol));
    EXPECT_TRUE(p.rotation.isApprox(Eigen::AngleAxisf(float(M_PI / 4), Vec3f::UnitY()).toRotationMatrix(), kTol));
  }
  // At a quarter: u = ¼ linearly, smoothstep(¼) = 5/32.
  EXPECT_NEAR(lin.at(1.5).scale, 1.0f + 2.0f * 0.25f, kTol);
  EXPECT_NEAR(smooth.at(1.5).scale, 1.0f + 2.0f * (5.0f / 32.0f), kTol);
  // Smoothstep starts and ends at rest: the speed near a keyframe falls toward zero, the linear one does not.
  const Vec3f x(2, 1, 0);
  const double h = 1e-3;
  auto speed = [&](const TargetMotion& m, double t) { return ((m.at(t + h).apply(x) - m.at(t).apply(x)) / float(h)).norm(); };
  EXPECT_LT(speed(smooth, 1.0), 0.02f);
  EXPECT_LT(speed(smooth, 3.0 - h), 0.02f);
  EXPECT_GT(speed(lin, 1.0), 1.0f);
  EXPECT_GT(speed(smooth, 2.0), speed(lin, 2.0));  // 1.5× the linear speed mid-way
}

TEST(TargetMotion, RestFromWorldUndoesThePose) {
  const TargetMotion m = two_keys(true);
  for (double t : {0.0, 1.7, 2.5, 9.0}) {
    const Pose p = m.at(t);
    for (const Vec3f& x : {Vec3f(0, 0, 0), Vec3f(2, 1, 0), Vec3f(-3, 0.5f, 7)})
      EXPECT_LT(((p.rest_from_world() * p.apply(x)) - x).norm(), 1e-5f) << t;  // absolute: x may be 0
  }
}

TEST(TargetMotion, ALivePoseReplacesTheKeyframesAboutTheTargetsPivot) {
  TargetMotion m = two_keys(false);
  Pose live = make_pose(Vec3f(0, 5, 0), Vec3f(0, 0, 0), 1.0f);
  live.pivot = Vec3f(100, 100, 100);  // ignored: the target's own pivot is used
  m.live = live;
  for (double t : {0.0, 2.0, 10.0}) {
    const Pose p = m.at(t);
    EXPECT_TRUE(p.pivot.isApprox(m.pivot));
    EXPECT_TRUE(p.apply(Vec3f(2, 1, 0)).isApprox(Vec3f(2, 6, 0), kTol));
  }
}

TEST(TargetMotion, KeyframesMustBeLaterEachTimeAndInRange) {
  TargetMotion m = two_keys(false);
  EXPECT_TRUE(m.validate("targets[0]").ok());
  m.keys[1].time = 1.0;
  Status st = m.validate("targets[0]");
  ASSERT_FALSE(st.ok());
  EXPECT_NE(st.error().message.find("targets[0].keyframes[1].time"), std::string::npos) << st.error().message;
  m.keys[1].time = 3.0;
  m.keys[0].scale = 0.0f;
  st = m.validate("targets[0]");
  ASSERT_FALSE(st.ok());
  EXPECT_NE(st.error().message.find("scale"), std::string::npos) << st.error().message;
  m.keys[0].scale = 1.0f;
  m.keys[0].translate.x() = NAN;
  EXPECT_FALSE(m.validate("targets[0]").ok());
}

}  // namespace
}  // namespace ff::pose
