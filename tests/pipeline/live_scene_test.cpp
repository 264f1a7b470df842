// The live scene behind `fluidform serve`: steps frame by frame, steers a target (the error rate is then measured
// against the moved target, and the pose is kept inside the domain), switches controllers, swaps the mesh for
// another from the list, and restarts — on a small sphere so that it runs in seconds.
#include "pipeline/live_scene.h"
#include "pipeline/live_scene_cases.h"
#include "scene/scene.h"
#include "support/test_support.h"

#include <gtest/gtest.h>

#include <cmath>

namespace ff::pipeline {
namespace {
namespace fs = std::filesystem;

TEST(LiveScene, StepSteerSwitchSwapRestart) {
  const fs::path dir = test::temp_dir("live-scene");
  auto made = test_cases::sphere_live_scene(dir, "cpu");
  ASSERT_TRUE(made) << made.error().message;
  LiveScene& s = **made;
  ASSERT_EQ(s.meshes().size(), 2u);
  ASSERT_EQ(s.targets().size(), 1u);
  EXPECT_EQ(s.controller_name(), "adaptive");
  const std::size_t n = s.particles().size();
  ASSERT_GT(n, 100u);

  double e_before = NAN;
  for (int k = 1; k <= 60; ++k) {
    auto f = s.step();
    ASSERT_TRUE(f) << f.error().message;
    EXPECT_EQ(f->frame, k);
    EXPECT_NEAR(f->time, k / s.fps(), 1e-9);
    e_before = f->error_rate;
  }
  ASSERT_TRUE(std::isfinite(e_before));

  // Moving the target by its own size: the next frame is measured against the moved target, so E jumps.
  const float size = s.targets()[0].box.max.x() - s.targets()[0].box.min.x();
  auto applied = s.set_pose(0, LivePose{Vec3f(size, 0, 0), Vec3f(0, 30, 0), 1.0f});
  ASSERT_TRUE(applied) << applied.error().message;
  EXPECT_FLOAT_EQ(applied->translate.x(), size);
  auto f = s.step();
  ASSERT_TRUE(f);
  EXPECT_GT(f->error_rate, e_before + 1.0) << "E is not measured against the moved target";
  // ... and the fluid follows it: E comes down again over the next second.
  double e_follow = f->error_rate;
  for (int k = 0; k < 60; ++k) e_follow = s.step()->error_rate;
  EXPECT_LT(e_follow, f->error_rate);

  // Far outside: clamped so that the target's centre stays in the domain.
  applied = s.set_pose(0, LivePose{Vec3f(1e5f, 0, 0), Vec3f::Zero(), 1.0f});
  ASSERT_TRUE(applied);
  EXPECT_LE(s.targets()[0].pivot.x() + applied->translate.x(), s.scene().domain.max.x() + 1e-5f);
  EXPECT_FALSE(s.set_pose(3, LivePose{}));
  EXPECT_FALSE(s.set_pose(0, LivePose{Vec3f(NAN, 0, 0), Vec3f::Zero(), 1.0f}));

  // Every registered controller can take over live, and steers.
  for (const char* name : {"none", "pbfc", "weighted", "thuerey", "rscf", "lcat", "adaptive"}) {
    ASSERT_TRUE(s.set_controller(name).ok()) << name;
    EXPECT_EQ(s.controller_name(), name);
    ASSERT_TRUE(s.set_pose(0, LivePose{Vec3f(0.5f * size, 0, 0), Vec3f::Zero(), 1.0f}));
    ASSERT_TRUE(s.step()) << name;
  }
  EXPECT_FALSE(s.set_controller("bogus").ok());
  EXPECT_EQ(s.controller_name(), "adaptive");

  // Swap to the box, then restart: the fluid is back, the box and the pose stay.
  ASSERT_TRUE(s.set_mesh(0, 1, core::null_progress()).ok());
  EXPECT_EQ(s.targets()[0].mesh, 1u);
  ASSERT_TRUE(s.step());
  EXPECT_FALSE(s.set_mesh(0, 5, core::null_progress()).ok());
  ASSERT_TRUE(s.restart().ok());
  EXPECT_EQ(s.frame(), 0);
  EXPECT_EQ(s.time(), 0.0);
  EXPECT_EQ(s.particles().size(), n);
  EXPECT_EQ(s.targets()[0].mesh, 1u);
  ASSERT_TRUE(s.step());
  fs::remove_all(dir);
}

}  // namespace
}  // namespace ff::pipeline
