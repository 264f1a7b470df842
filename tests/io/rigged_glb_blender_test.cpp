// The rigged GLB (io/write_rigged_glb.h) of the hand-built skinned bar (tests/support/skin_bar.h) in Blender (Debian's
// 3.4, headless, through scripts/blender_rig_check.py): an armature with every clip comes in, the mesh is bound to it
// by an Armature modifier, and playing "bend" deforms it: the evaluated mesh's bounds at three times differ from one
// another and match the C++ pose (LBS with T · K · T⁻¹) within 2 % of the size, under each of the tests' transforms.
// Skipped, saying so, where Blender is not installed.
#include "io/write_rigged_glb.h"

#include "io/load_mesh.h"
#include "support/skin_bar.h"
#include "support/test_support.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

namespace ff::io {
namespace {

using nlohmann::json;

TEST(RiggedGlbBlender, ImportsAnArmatureWithTheClipsAndTheMeshDeformsAsTheCppPose) {
  if (test::shell("PATH=/usr/bin:$PATH command -v blender").first != 0)
    GTEST_SKIP() << "Blender is not installed (apt-get install blender): the Blender import of rigged.glb is not checked";
  const auto dir = test::temp_dir("rigged-blender");
  const std::vector<double> times = {0.0, 0.5, 1.0};
  int k = 0;
  for (const MeshTransform& t : test::rig_transforms()) {
    SCOPED_TRACE("transform " + std::to_string(k));
    TriangleMesh scene = test::bar_mesh(20, 24);
    const Skin skin = test::bar_skin(scene);
    TriangleMesh world = scene;
    transform_mesh(world, t);
    const auto path = dir / ("bar" + std::to_string(k++) + ".glb");
    ASSERT_TRUE(write_rigged_glb(path, world, skin.joints, skin.weights, skin, t, Vec3f(0.2f, 0.5f, 0.8f)).ok());
    const auto [rc, out] = test::shell(
        "PATH=/usr/bin:$PATH timeout 600 blender -b --factory-startup -noaudio --python-exit-code 1 -P '" +
        (test::source_dir() / "scripts" / "blender_rig_check.py").string() + "' -- --glb '" + path.string() +
        "' --clip bend --times 0,0.5,1");
    const std::string prefix = "FLUIDFORM_RIG ";
    const auto at = out.find(prefix);
    ASSERT_NE(at, std::string::npos) << out;
    const json j = json::parse(out.substr(at + prefix.size(), out.find('\n', at) - at - prefix.size()), nullptr, false);
    ASSERT_FALSE(j.is_discarded()) << out;
    ASSERT_EQ(rc, 0) << out;
    EXPECT_EQ(j["armatures"], 1) << out;
    EXPECT_EQ(j["skinned_meshes"], 1) << out;
    EXPECT_GE(j["vertex_groups"].get<int>(), 2) << out;
    bool bend = false, wave = false;
    for (const auto& a : j["actions"]) {
      bend |= a["name"].get<std::string>().rfind("bend", 0) == 0;
      wave |= a["name"].get<std::string>().rfind("wave", 0) == 0;
    }
    EXPECT_TRUE(bend && wave) << out;
    ASSERT_EQ(j["poses"].size(), times.size()) << out;
    std::vector<Aabb> want;
    for (double time : times) want.push_back(test::bounds_of(test::pose_world(world, skin.joints, skin.weights, skin, t, 0, time)));
    for (std::size_t i = 0; i < times.size(); ++i) {
      const double tol = 0.02 * want[i].size().norm();
      for (int a = 0; a < 3; ++a) {
        EXPECT_NEAR(j["poses"][i]["min"][a].get<double>(), want[i].min[a], tol) << "t=" << times[i] << " " << out;
        EXPECT_NEAR(j["poses"][i]["max"][a].get<double>(), want[i].max[a], tol) << "t=" << times[i] << " " << out;
      }
    }
    // It deforms: the box at the clip's end is not the one at its start (the bar bends 90°).
    double moved = 0.0;
    for (int a = 0; a < 3; ++a)
      moved = std::max({moved, std::abs(j["poses"][2]["min"][a].get<double>() - j["poses"][0]["min"][a].get<double>()),
                        std::abs(j["poses"][2]["max"][a].get<double>() - j["poses"][0]["max"][a].get<double>())});
    EXPECT_GT(moved, 0.2 * want[0].size().norm()) << out;
  }
}

}  // namespace
}  // namespace ff::io
