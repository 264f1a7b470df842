// The live scene behind `fluidform serve --device gpu` on the machine's Vulkan device (lavapipe in CI): it steps on
// the device, a steered target (static until then) is followed there, a controller the GPU path does not have is a
// one-line error that keeps the running one, and switching, swapping the mesh and restarting rebuild it on the device.
#include "pipeline/live_scene.h"
#include "pipeline/live_scene_cases.h"
#include "scene/scene.h"
#include "support/test_support.h"

#include <gtest/gtest.h>

#include <cmath>

namespace ff::pipeline {
namespace {
namespace fs = std::filesystem;

TEST(LiveSceneGpu, StepsSteersSwitchesAndRestartsOnTheDevice) {
  const fs::path dir = test::temp_dir("live-scene-gpu");
  auto made = test_cases::sphere_live_scene(dir, "gpu");
  ASSERT_TRUE(made) << made.error().message;
  LiveScene& s = **made;
  EXPECT_NE(s.device(), "cpu");
  EXPECT_EQ(s.controller_name(), "adaptive");
  const std::size_t n = s.particles().size();

  double e_before = NAN;
  for (int k = 1; k <= 60; ++k) {
    auto f = s.step();
    ASSERT_TRUE(f) << f.error().message;
    e_before = f->error_rate;
  }
  ASSERT_TRUE(std::isfinite(e_before));
  EXPECT_GT(s.step()->controlled, n / 2) << "the sphere should have caught most of the fluid";

  // Steering the (so far static) target by its own size: E jumps, then comes down as the fluid follows on the device.
  const float size = s.targets()[0].box.max.x() - s.targets()[0].box.min.x();
  ASSERT_TRUE(s.set_pose(0, LivePose{Vec3f(size, 0, 0), Vec3f(0, 30, 0), 1.0f}));
  auto f = s.step();
  ASSERT_TRUE(f) << f.error().message;
  EXPECT_GT(f->error_rate, e_before + 1.0);
  double e_follow = f->error_rate;
  for (int k = 0; k < 60; ++k) e_follow = s.step()->error_rate;
  std::printf("on %s: E %.2f %% formed, %.2f %% right after the steer, %.2f %% a second later\n", s.device().c_str(),
              e_before, f->error_rate, e_follow);
  EXPECT_LT(e_follow, 0.5 * f->error_rate);

  // A baseline is CPU-only: one line, and the adaptive controller keeps running on the device.
  const Status pbfc = s.set_controller("pbfc");
  ASSERT_FALSE(pbfc.ok());
  EXPECT_NE(pbfc.error().message.find("does not do the controller 'pbfc'"), std::string::npos) << pbfc.error().message;
  EXPECT_EQ(pbfc.error().message.find('\n'), std::string::npos);
  EXPECT_EQ(s.controller_name(), "adaptive");
  ASSERT_TRUE(s.step());
  for (const char* name : {"none", "adaptive"}) {
    ASSERT_TRUE(s.set_controller(name).ok()) << name;
    EXPECT_EQ(s.controller_name(), name);
    EXPECT_NE(s.device(), "cpu");
    ASSERT_TRUE(s.step()) << name;
  }
  ASSERT_TRUE(s.set_mesh(0, 1, core::null_progress()).ok());
  ASSERT_TRUE(s.step());
  ASSERT_TRUE(s.restart().ok());
  EXPECT_EQ(s.particles().size(), n);
  auto again = s.step();
  ASSERT_TRUE(again) << again.error().message;
  EXPECT_EQ(again->frame, 1);
  EXPECT_NE(s.device(), "cpu");
  fs::remove_all(dir);
}

TEST(LiveSceneGpu, AControllerTheDeviceDoesNotHaveIsRefusedUpFront) {
  const fs::path dir = test::temp_dir("live-scene-gpu-refused");
  test::write_obj(dir / "sphere.obj", test::sphere_mesh(1.0f, 3));
  auto scene = scene::parse_scene(R"({"targets": [{"mesh": "sphere.obj", "scale": 0.15}], "sampling": {"auto_count": 600},
                                      "controller": {"name": "thuerey"}})", dir);
  ASSERT_TRUE(scene) << scene.error().message;
  LiveOptions lo;
  lo.cache_dir = dir / "cache";
  lo.device = "gpu";
  auto made = LiveScene::create(*scene, lo, core::null_progress());
  ASSERT_FALSE(made);
  EXPECT_NE(made.error().message.find("thuerey"), std::string::npos) << made.error().message;
  lo.device = "tpu";
  auto bad = LiveScene::create(*scene, lo, core::null_progress());
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.error().message.find("expected cpu, gpu or auto"), std::string::npos) << bad.error().message;
  fs::remove_all(dir);
}

}  // namespace
}  // namespace ff::pipeline
