#pragma once
// The live-scene tests' scene (tests/pipeline/live_scene_test.cpp on the CPU, live_scene_gpu_test.cpp on the device):
// a small sphere (600 samples) with a box in the mesh list, so that it forms in seconds and can swap its mesh.
#include "pipeline/live_scene.h"
#include "scene/scene.h"
#include "support/test_support.h"

#include <filesystem>
#include <memory>
#include <string>

namespace ff::pipeline::test_cases {

/// The sphere scene in `dir` (its meshes written there), on `device`.
inline Result<std::unique_ptr<LiveScene>> sphere_live_scene(const std::filesystem::path& dir, const std::string& device) {
  test::write_obj(dir / "sphere.obj", test::sphere_mesh(1.0f, 3));
  test::write_obj(dir / "box.obj", test::box_mesh(Vec3f(-0.8f, -0.8f, -0.8f), Vec3f(0.8f, 0.8f, 0.8f)));
  FF_TRY(const scene::Scene scene,
         scene::parse_scene(R"({"targets": [{"mesh": "sphere.obj", "scale": 0.15}], "sampling": {"auto_count": 600}})",
                            dir));
  LiveOptions lo;
  lo.cache_dir = dir / "cache";
  lo.extra_meshes = {dir / "box.obj"};
  lo.device = device;
  return LiveScene::create(scene, lo, core::null_progress());
}

}  // namespace ff::pipeline::test_cases
