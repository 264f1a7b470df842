// Skinning checked by an independent path (issue 19): Blender 3.4 imports the skinned file with its own importer,
// plays the clip with its own Armature modifier (scripts/blender_pose_export.py), and the control samples that
// fluidform posed (io/skin + pose/skinning, diffusion weights, linear blending) must lie inside Blender's posed mesh:
// of the samples inside the bind mesh, ≥ 99 % at every time, on the walking demo character (glTF); both paths' posed
// meshes must also agree (bounds within 1 % of the size; measured ~1e-5 %). huesitos.fbx is not a case: Blender's FBX
// importer and Assimp pose it differently (bounds 3–7.5 % of its size apart at four clip times), so neither is a
// reference for the other there. Skipped, saying so, where Blender is not installed.
#include "io/load_mesh.h"
#include "pipeline/skinned_setup.h"
#include "sampling/mesh_field.h"
#include "support/test_support.h"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <ostream>

namespace ff::pipeline {
namespace {
namespace fs = std::filesystem;

struct BlenderCase {
  std::string name;
  std::string file;    // empty: the generated character
  std::string clip;    // fluidform's clip
  std::string action;  // Blender's action name prefix ("" = the first)
  float scale;
  double keep_inside;
};

// A stable ctest name: printed as its name, not as raw bytes (why: PrintTo in tests/e2e/character_test.cpp).
void PrintTo(const BlenderCase& c, std::ostream* os) { *os << c.name; }

class SkinnedBlender : public ::testing::TestWithParam<BlenderCase> {};

TEST_P(SkinnedBlender, PosedSamplesLieInsideBlendersPoseOfTheSameClip) {
  const BlenderCase& c = GetParam();
  if (test::shell("PATH=/usr/bin:$PATH command -v blender").first != 0)
    GTEST_SKIP() << "Blender is not installed (apt-get install blender): skinning is not checked against Blender's pose";
  const auto dir = test::temp_dir("skinned-blender-" + c.name);
  fs::path file = c.file;
  if (file.empty()) {
    file = dir / "character.glb";
    ASSERT_EQ(std::system(fmt::format("/usr/bin/python3 {}/scripts/make_character.py --out {} > /dev/null",
                                      test::source_dir().string(), file.string()).c_str()), 0);
  }
  ASSERT_TRUE(fs::exists(file)) << file;
  auto setup = test::skinned_setup(file, c.clip, c.scale, dir);
  ASSERT_TRUE(setup.has_value()) << setup.error().message;
  const auto& sk = setup->skinned();
  auto bind_field = sampling::MeshField::build(sk.bind_mesh);
  ASSERT_TRUE(bind_field.has_value());
  std::vector<double> times;
  const double duration = sk.skin->skin.clips[static_cast<std::size_t>(sk.skin->clip)].duration;
  for (int k = 1; k <= 4; ++k) times.push_back(duration * k / 5.0);
  const auto [rc, out] = test::shell(fmt::format(
      "PATH=/usr/bin:$PATH timeout 600 blender -b --factory-startup -noaudio --python-exit-code 1 -P '{}' -- --file '{}' "
      "--out '{}' --action '{}' --times {},{},{},{}",
      (test::source_dir() / "scripts" / "blender_pose_export.py").string(), file.string(), (dir / "posed").string(),
      c.action, times[0], times[1], times[2], times[3]));
  ASSERT_EQ(rc, 0) << out;
  ASSERT_NE(out.find("FLUIDFORM_POSE "), std::string::npos) << out;
  for (std::size_t k = 0; k < times.size(); ++k) {
    // Blender's pose, in the file's units: scaled as the target is (the FBX importer already turned centimetres into
    // metres, which is the 0.01 the scene gives huesitos: its OBJ is not scaled again).
    auto theirs = io::load_mesh(dir / fmt::format("posed_{}.obj", k));
    ASSERT_TRUE(theirs.has_value()) << theirs.error().message;
    if (fs::path(file).extension() != ".fbx")
      for (auto& v : theirs->vertices) v *= c.scale;
    auto field = sampling::MeshField::build(*theirs);
    ASSERT_TRUE(field.has_value()) << field.error().message;
    // Ours: the bind mesh and samples skinned at the same time.
    std::vector<io::Mat4f> K;
    sk.skin->world_joint_matrices(times[k], K);
    pose::PosedJoints joints;
    joints.set(K, sk.skin->spec.skinning);
    Aabb mine;
    for (std::size_t v = 0; v < sk.bind_mesh.vertices.size(); ++v)
      mine.extend(joints.apply(sk.mesh_joints[v], sk.mesh_weights[v], sk.bind_mesh.vertices[v]));
    const Aabb b = theirs->bounds();
    const float tol = 0.01f * mine.size().norm();
    for (int a = 0; a < 3; ++a) {
      EXPECT_NEAR(b.min[a], mine.min[a], tol) << "t = " << times[k] << ", axis " << a;
      EXPECT_NEAR(b.max[a], mine.max[a], tol) << "t = " << times[k] << ", axis " << a;
    }
    const std::vector<Vec3f> x = posed_samples(sk, times[k], sk.skin->spec.skinning);
    std::size_t in = 0, kept = 0;
    for (std::size_t i = 0; i < sk.bind_samples.size(); ++i) {
      if (!bind_field->inside(sk.bind_samples[i])) continue;
      ++in;
      kept += field->inside(x[i]);
    }
    const double share = double(kept) / double(in);
    double gap = 0.0;
    for (int a = 0; a < 3; ++a) gap = std::max({gap, double(std::abs(b.min[a] - mine.min[a])), double(std::abs(b.max[a] - mine.max[a]))});
    std::printf("%s t=%.3f: %.2f %% of %zu samples inside Blender's posed mesh; its bounds and ours %.2g m apart (%.2g %% of the size)\n",
                c.name.c_str(), times[k], 100.0 * share, in, gap, 100.0 * gap / mine.size().norm());
    EXPECT_GE(share, c.keep_inside) << "t = " << times[k];
  }
}

INSTANTIATE_TEST_SUITE_P(
    Files, SkinnedBlender,
    ::testing::Values(BlenderCase{"character", "", "walk", "walk", 1.0f, 0.99}),
    [](const ::testing::TestParamInfo<BlenderCase>& p) { return p.param.name; });

}  // namespace
}  // namespace ff::pipeline
