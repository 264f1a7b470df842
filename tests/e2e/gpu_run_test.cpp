// `fluidform run --device gpu|auto` end to end on the machine's Vulkan device (lavapipe in CI): a small forming scene
// gives the CPU's quality figures, two runs give the same frames, a checkpoint resumes to the same last frame, what
// the GPU path does not do (a baseline controller) is a one-line error, and auto never picks lavapipe.
#include "e2e/cli_support.h"
#include "io/write_ply.h"
#include "support/test_support.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <tuple>
#include <utility>

namespace ff {
namespace {
namespace fs = std::filesystem;
using namespace e2e;
using nlohmann::json;

// A sphere of radius 0.25 m as the target, ~1500 particles, the solver's defaults (surface tension and drag on).
fs::path forming_scene(const fs::path& dir, const std::string& solver = R"("viscosity": 0.01)") {
  test::write_obj(dir / "sphere.obj", test::sphere_mesh(0.25f, 3));
  return write_scene(dir, R"({
    "targets": [{"mesh": "sphere.obj"}],
    "sampling": {"auto_count": 1500},
    "solver": {)" + solver + R"(},
    "output": {"frames": 24, "checkpoint_every": 8}
  })");
}

json report(const fs::path& out) { return json::parse(read_file(out / "report.json")); }

std::string frame(const fs::path& out, int f) {
  char name[32];
  std::snprintf(name, sizeof name, "frame_%05d.ply", f);
  return read_file(out / "particles" / name);
}

TEST(GpuRun, FormsAsTheCpuDoesRepeatsBitForBitAndResumes) {
  const auto dir = test::temp_dir("gpu_run");
  const fs::path scene = forming_scene(dir);
  const auto gpu = run({"run", scene.string(), "-o", (dir / "gpu").string(), "--device", "gpu", "--no-mesh"});
  ASSERT_EQ(gpu.code, 0) << gpu.err;
  const auto cpu = run({"-q", "run", scene.string(), "-o", (dir / "cpu").string(), "--device", "cpu", "--no-mesh"});
  ASSERT_EQ(cpu.code, 0) << cpu.err;
  const json g = report(dir / "gpu"), c = report(dir / "cpu");
  EXPECT_EQ(c["device"], "cpu");
  ASSERT_TRUE(g["device"].is_string());
  EXPECT_NE(g["device"].get<std::string>(), "cpu");
  const json &gt = g["totals"], &ct = c["totals"];
  std::printf("device %s\n  E %.3f %% vs CPU %.3f %%, inside %.2f %% vs %.2f %%, splash %.2f %% vs %.2f %%\n",
              g["device"].get<std::string>().c_str(), gt["error_rate_pct"].get<double>(), ct["error_rate_pct"].get<double>(),
              100 * gt["inside_fraction"].get<double>(), 100 * ct["inside_fraction"].get<double>(),
              100 * gt["splash_fraction"].get<double>(), 100 * ct["splash_fraction"].get<double>());
  EXPECT_NEAR(gt["error_rate_pct"].get<double>(), ct["error_rate_pct"].get<double>(),
              0.1 * ct["error_rate_pct"].get<double>());
  EXPECT_NEAR(gt["inside_fraction"].get<double>(), ct["inside_fraction"].get<double>(), 0.02);
  EXPECT_NEAR(gt["splash_fraction"].get<double>(), ct["splash_fraction"].get<double>(), 0.02);

  // The same run again: the same bits.
  const auto again = run({"-q", "run", scene.string(), "-o", (dir / "again").string(), "--device", "gpu", "--no-mesh"});
  ASSERT_EQ(again.code, 0) << again.err;
  for (int f : {1, 12, 24}) EXPECT_TRUE(frame(dir / "gpu", f) == frame(dir / "again", f)) << "frame " << f << " differs";

  // Resume from the checkpoint before the last (frame 16): frames 17–24 again, the same last frame.
  fs::copy_file(dir / "again" / "checkpoint" / "state.prev.ffck", dir / "again" / "checkpoint" / "state.ffck",
                fs::copy_options::overwrite_existing);
  fs::remove(dir / "again" / "particles" / "frame_00024.ply");
  const auto resumed =
      run({"run", scene.string(), "-o", (dir / "again").string(), "--device", "gpu", "--no-mesh", "--resume"});
  ASSERT_EQ(resumed.code, 0) << resumed.err;
  EXPECT_NE(resumed.err.find("resuming from frame"), std::string::npos) << resumed.err;
  EXPECT_TRUE(frame(dir / "gpu", 24) == frame(dir / "again", 24)) << "the resumed last frame differs";
  expect_no_temp_files(dir / "gpu");
}

// Faults injected at the Vulkan calls (gpu::FaultPlan, FF_GPU_FAULT): the error code a failing driver returns, and
// the run takes its ordinary error path. Each is one line naming the cause, with a non-zero exit and no temporary
// file; a device lost mid-run leaves the checkpoints, from which --resume finishes on the CPU and on the GPU.
struct FaultEnv {
  explicit FaultEnv(const char* v) { setenv("FF_GPU_FAULT", v, 1); }
  ~FaultEnv() { unsetenv("FF_GPU_FAULT"); }
};

TEST(GpuRun, ADeviceLostOutOfMemoryOrABadShaderIsOneLineAndTheRunResumes) {
  const auto dir = test::temp_dir("gpu_faults");
  const fs::path scene = forming_scene(dir);  // 24 frames, a checkpoint every 8
  auto one_line = [](const Outcome& r, const std::string& cause) {
    EXPECT_NE(r.code, 0);
    EXPECT_NE(r.err.find(cause), std::string::npos) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  };
  {
    // ~10 submissions a frame (the frame, the downloads): the device is lost at frame 15, after the checkpoint at 8.
    const FaultEnv lost("device-lost:150");
    for (const char* out : {"lost_cpu", "lost_gpu"}) {
      const auto r = run({"-q", "run", scene.string(), "-o", (dir / out).string(), "--device", "gpu", "--no-mesh"});
      one_line(r, "VK_ERROR_DEVICE_LOST");
      EXPECT_TRUE(fs::exists(dir / out / "particles" / "frame_00008.ply"));
      EXPECT_FALSE(fs::exists(dir / out / "particles" / "frame_00024.ply"));
      EXPECT_TRUE(fs::exists(dir / out / "checkpoint" / "state.ffck"));
      expect_no_temp_files(dir / out);
    }
  }
  for (const auto& [out, device] : {std::pair{"lost_cpu", "cpu"}, std::pair{"lost_gpu", "gpu"}}) {
    const auto r = run({"run", scene.string(), "-o", (dir / out).string(), "--device", device, "--no-mesh", "--resume"});
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_NE(r.err.find("resuming from frame"), std::string::npos) << r.err;
    EXPECT_TRUE(fs::exists(dir / out / "particles" / "frame_00024.ply")) << out;
    EXPECT_EQ(report(dir / out)["device"] == "cpu", std::string(device) == "cpu") << out;
    expect_no_temp_files(dir / out);
  }
  {
    const FaultEnv oom("out-of-memory:3");
    const auto r = run({"-q", "run", scene.string(), "-o", (dir / "oom").string(), "--device", "gpu", "--no-mesh"});
    one_line(r, "VK_ERROR_OUT_OF_DEVICE_MEMORY");
    EXPECT_FALSE(fs::exists(dir / "oom" / "particles" / "frame_00001.ply"));
    if (fs::exists(dir / "oom")) expect_no_temp_files(dir / "oom");
  }
  {
    const FaultEnv shader("shader:pbf_lambda");
    const auto r = run({"-q", "run", scene.string(), "-o", (dir / "shader").string(), "--device", "gpu", "--no-mesh"});
    one_line(r, "loading shader pbf_lambda failed (VK_ERROR_INVALID_SHADER_NV)");
    if (fs::exists(dir / "shader")) expect_no_temp_files(dir / "shader");
  }
  {
    // A GPU that allows fewer storage buffers per shader than the control's spring pass binds (14; the fluid's passes
    // bind at most 9 and Vulkan guarantees 4): that pass names itself, the count and the limit, before any frame.
    const FaultEnv small("storage-buffers:13");
    const auto r = run({"-q", "run", scene.string(), "-o", (dir / "small").string(), "--device", "gpu", "--no-mesh"});
    one_line(r, "shader ctl_spring binds 14 storage buffers and");
    EXPECT_NE(r.err.find("allows 13 per shader"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(dir / "small" / "particles" / "frame_00001.ply"));
    if (fs::exists(dir / "small")) expect_no_temp_files(dir / "small");
  }
  const FaultEnv bad("device-lost:soon");
  const auto r = run({"-q", "run", scene.string(), "-o", (dir / "bad").string(), "--device", "gpu", "--no-mesh"});
  one_line(r, "FF_GPU_FAULT");
}

// A morph (targets[].morph): the sphere swaps at 0.1 s to a box of about its volume beside it (+x). The device run
// takes the box's samples at the swap's sub-step: its fluid moves toward the box as the CPU's does (the mean x of the
// last frame's particles), far from where the same scene without the morph leaves it (on the CPU), with the CPU's
// figures.
TEST(GpuRun, AMorphRunsOnTheDeviceAsOnTheCpu) {
  const auto dir = test::temp_dir("gpu_morph");
  test::write_obj(dir / "sphere.obj", test::sphere_mesh(0.25f, 3));
  test::write_obj(dir / "box.obj", test::box_mesh(Vec3f(0.1f, -0.2f, -0.2f), Vec3f(0.5f, 0.2f, 0.2f)));
  const auto scene = [&](const std::string& name, const std::string& morph) {
    return write_scene(dir, R"({
      "targets": [{"mesh": "sphere.obj")" + morph + R"(}],
      "sampling": {"auto_count": 1500},
      "output": {"frames": 30}
    })", name);
  };
  const fs::path morph = scene("morph.json", R"(, "morph": [{"time": 0.1, "mesh": "box.obj"}])");
  const fs::path still = scene("still.json", "");
  const auto mean_x = [&](const fs::path& out) {
    auto last = io::read_particles_ply(out / "particles" / "frame_00030.ply");
    EXPECT_TRUE(last.has_value());
    double sum = 0;
    for (const Vec3f& x : last->positions) sum += x.x();
    return last->positions.empty() ? 0.0 : sum / double(last->positions.size());
  };
  const std::tuple<fs::path, const char*, const char*> runs[] = {
      {morph, "gpu", "gpu"}, {morph, "cpu", "cpu"}, {still, "still", "cpu"}};  // the reference on the CPU: 1 s, not 12
  for (const auto& [s, out, device] : runs) {
    const auto r = run({"-q", "run", s.string(), "-o", (dir / out).string(), "--device", device, "--no-mesh"});
    ASSERT_EQ(r.code, 0) << r.err;
  }
  const json g = report(dir / "gpu"), c = report(dir / "cpu");
  const json &gt = g["totals"], &ct = c["totals"];
  const double gx = mean_x(dir / "gpu"), cx = mean_x(dir / "cpu"), sx = mean_x(dir / "still");
  std::printf("morph on the device: E %.3f %% vs CPU %.3f %%, inside %.2f %% vs %.2f %%; mean x %.4f m vs CPU %.4f, "
              "without the morph (CPU) %.4f\n",
              gt["error_rate_pct"].get<double>(), ct["error_rate_pct"].get<double>(),
              100 * gt["inside_fraction"].get<double>(), 100 * ct["inside_fraction"].get<double>(), gx, cx, sx);
  EXPECT_NEAR(gt["error_rate_pct"].get<double>(), ct["error_rate_pct"].get<double>(),
              0.1 * ct["error_rate_pct"].get<double>());
  EXPECT_NEAR(gt["inside_fraction"].get<double>(), ct["inside_fraction"].get<double>(), 0.02);
  EXPECT_GT(gx - sx, 10 * std::abs(gx - cx));
}

TEST(GpuRun, WhatTheGpuDoesNotDoYetIsAOneLineErrorAndAutoFallsBack) {
  const auto dir = test::temp_dir("gpu_gaps");
  test::write_obj(dir / "sphere.obj", test::sphere_mesh(0.25f, 3));
  const fs::path scene = write_scene(dir, R"({
    "targets": [{"mesh": "sphere.obj"}],
    "sampling": {"auto_count": 1500},
    "controller": {"name": "pbfc"}
  })");  // the baselines stay on the CPU
  const auto r = run({"-q", "run", scene.string(), "-o", (dir / "out").string(), "--device", "gpu", "--frames", "2"});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("does not do the controller 'pbfc'"), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_FALSE(fs::exists(dir / "out")) << "checked before anything is written";
  const auto bad = run({"run", scene.string(), "-o", (dir / "bad").string(), "--device", "tpu"});
  EXPECT_EQ(bad.code, 2) << bad.err;
  // auto: the CPU whenever the scene asks for what the GPU path does not do, or there is no discrete or integrated
  // GPU (lavapipe alone is slower than the CPU path).
  const auto a = run({"run", scene.string(), "-o", (dir / "auto").string(), "--device", "auto", "--frames", "2", "--no-mesh"});
  ASSERT_EQ(a.code, 0) << a.err;
  EXPECT_EQ(report(dir / "auto")["device"], "cpu");
  EXPECT_NE(a.err.find("--device auto"), std::string::npos) << a.err;
}

}  // namespace
}  // namespace ff
