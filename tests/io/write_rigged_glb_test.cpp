// The rigged GLB (io/write_rigged_glb.h) of the hand-built skinned bar (tests/support/skin_bar.h): its layout read back
// from the bytes, one-line errors, the Khronos validator's verdict and three.js's pose of it against the C++ pose
// (LBS with T · K · T⁻¹) at three times of a clip, under an identity, a scaled-rotated-moved and a mirroring T.
#include "io/write_rigged_glb.h"

#include "io/load_mesh.h"
#include "support/skin_bar.h"
#include "support/test_support.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cstring>
#include <fstream>
#include <memory>

namespace ff::io {
namespace {

using nlohmann::json;

std::uint32_t u32(const std::vector<std::uint8_t>& b, std::size_t at) {
  std::uint32_t v;
  std::memcpy(&v, b.data() + at, 4);
  return v;
}
json glb_json(const std::vector<std::uint8_t>& b) {
  const std::uint32_t len = u32(b, 12);
  return json::parse(b.begin() + 20, b.begin() + 20 + len);
}
/// The bytes of accessor `a` (tightly packed: our writer never strides these).
template <class T>
std::vector<T> accessor_data(const std::vector<std::uint8_t>& b, const json& doc, int a, int components) {
  const json& acc = doc["accessors"][a];
  const json& view = doc["bufferViews"][acc["bufferView"].get<int>()];
  const std::size_t bin = 20 + u32(b, 12) + 8;
  const std::size_t at = bin + view["byteOffset"].get<std::size_t>();
  std::vector<T> out(acc["count"].get<std::size_t>() * static_cast<std::size_t>(components));
  std::memcpy(out.data(), b.data() + at, out.size() * sizeof(T));
  return out;
}

struct Rig {
  TriangleMesh scene, world;
  Skin skin;
};
Rig bar_rig(const MeshTransform& t) {
  Rig r;
  r.scene = test::bar_mesh(20, 24);
  r.skin = test::bar_skin(r.scene);
  r.world = r.scene;
  transform_mesh(r.world, t);
  return r;
}

TEST(RiggedGlb, HoldsTheSkeletonSkinClipsAndTheMeshInTheFilesSpace) {
  const MeshTransform t = test::rig_transforms()[1];
  const Rig r = bar_rig(t);
  auto bytes = encode_rigged_glb(r.world, r.skin.joints, r.skin.weights, r.skin, t, Vec3f(0.2f, 0.5f, 0.8f));
  ASSERT_TRUE(bytes.has_value()) << bytes.error().message;
  const json doc = glb_json(*bytes);
  ASSERT_EQ(doc["nodes"].size(), 5u);  // rig root, three skeleton nodes, the mesh
  EXPECT_EQ(doc["nodes"][0]["name"], "fluidform_rig");
  EXPECT_EQ(doc["nodes"][0]["children"], json::array({1}));
  EXPECT_EQ(doc["nodes"][1]["name"], "Armature");
  EXPECT_EQ(doc["nodes"][1]["children"], json::array({2}));
  EXPECT_EQ(doc["nodes"][2]["children"], json::array({3}));
  EXPECT_EQ(doc["nodes"][4]["skin"], 0);
  EXPECT_EQ(doc["scenes"][0]["nodes"], json::array({0, 4}));
  EXPECT_FALSE(doc["nodes"][4].contains("translation"));
  // The root's TRS is T: its matrix maps a scene point as MeshTransform::apply does.
  const json& root = doc["nodes"][0];
  const Quatf q(root["rotation"][3].get<float>(), root["rotation"][0].get<float>(), root["rotation"][1].get<float>(),
                root["rotation"][2].get<float>());
  const Vec3f s(root["scale"][0].get<float>(), root["scale"][1].get<float>(), root["scale"][2].get<float>());
  const Vec3f tr(root["translation"][0].get<float>(), root["translation"][1].get<float>(), root["translation"][2].get<float>());
  for (const Vec3f& p : {Vec3f(1, 2, 3), Vec3f(-0.5f, 0.1f, 0.7f)})
    EXPECT_LT((q * s.cwiseProduct(p) + tr - t.apply(p)).norm(), 1e-5f);
  EXPECT_EQ(doc["skins"][0]["joints"], json::array({2, 3}));
  EXPECT_EQ(doc["skins"][0]["skeleton"], 0);
  ASSERT_EQ(doc["animations"].size(), 2u);
  EXPECT_EQ(doc["animations"][0]["name"], "bend");
  EXPECT_EQ(doc["animations"][1]["name"], "wave");
  EXPECT_EQ(doc["animations"][0]["channels"].size(), 3u);  // root translation, mid rotation and scale
  for (const auto& sampler : doc["animations"][0]["samplers"]) {
    EXPECT_EQ(sampler["interpolation"], "LINEAR");
    EXPECT_FLOAT_EQ(doc["accessors"][sampler["input"].get<int>()]["max"][0].get<float>(), 1.0f);  // held to the end
  }
  // Positions are the scene-space bar (T⁻¹ of the world mesh); joints and weights as given.
  const json& attr = doc["meshes"][0]["primitives"][0]["attributes"];
  EXPECT_EQ(doc["accessors"][attr["JOINTS_0"].get<int>()]["componentType"], 5123);
  EXPECT_EQ(doc["accessors"][attr["WEIGHTS_0"].get<int>()]["componentType"], 5126);
  const auto pos = accessor_data<float>(*bytes, doc, attr["POSITION"].get<int>(), 3);
  const auto w = accessor_data<float>(*bytes, doc, attr["WEIGHTS_0"].get<int>(), 4);
  const auto j = accessor_data<std::uint16_t>(*bytes, doc, attr["JOINTS_0"].get<int>(), 4);
  ASSERT_EQ(pos.size(), 3 * r.scene.vertices.size());
  float worst = 0.0f;
  for (std::size_t v = 0; v < r.scene.vertices.size(); ++v) {
    worst = std::max(worst, (Vec3f(pos[3 * v], pos[3 * v + 1], pos[3 * v + 2]) - r.scene.vertices[v]).norm());
    for (int k = 0; k < 4; ++k) {
      EXPECT_EQ(j[4 * v + k], r.skin.joints[v][k]);
      EXPECT_FLOAT_EQ(w[4 * v + k], r.skin.weights[v][k]);
    }
  }
  EXPECT_LT(worst, 1e-5f);
  // Inverse bind matrices as the skin's, column-major.
  const auto ibm = accessor_data<float>(*bytes, doc, doc["skins"][0]["inverseBindMatrices"].get<int>(), 16);
  for (std::size_t k = 0; k < 2; ++k)
    for (int e = 0; e < 16; ++e) EXPECT_FLOAT_EQ(ibm[16 * k + e], r.skin.inverse_bind[k].data()[e]);
}

// A rigged mesh in its target's texture: split at the UVs' seam only, every copy with its vertex's joints and weights,
// TEXCOORD_0 and the texture embedded under the one material.
TEST(RiggedGlb, ATexturedMeshKeepsEachCopysInfluences) {
  const MeshTransform t = test::rig_transforms()[0];
  Rig r = bar_rig(t);
  auto texture = std::make_shared<MeshTexture>();
  texture->image.width = 2, texture->image.height = 2, texture->image.rgb.assign(12, 128);
  r.world.texture = texture;
  // UVs from x, with the triangles of the bar's first half on the left of the texture and the rest on the right: the
  // vertices the two halves share get two UVs.
  const std::size_t half = r.world.triangles.size() / 2;
  for (std::size_t k = 0; k < r.world.triangles.size(); ++k) {
    std::array<Vec2f, 3> uv;
    for (int c = 0; c < 3; ++c) uv[std::size_t(c)] = Vec2f(k < half ? 0.25f : 0.75f, r.world.vertices[r.world.triangles[k][std::size_t(c)]].y());
    r.world.corner_uv.push_back(uv);
  }
  auto bytes = encode_rigged_glb(r.world, r.skin.joints, r.skin.weights, r.skin, t, Vec3f::Ones());
  ASSERT_TRUE(bytes.has_value()) << bytes.error().message;
  const json doc = glb_json(*bytes);
  const json& attributes = doc["meshes"][0]["primitives"][0]["attributes"];
  ASSERT_TRUE(attributes.contains("TEXCOORD_0"));
  EXPECT_FALSE(attributes.contains("COLOR_0"));
  EXPECT_EQ(doc["images"].size(), 1u);
  EXPECT_EQ(doc["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"]["index"], 0);
  const auto n = doc["accessors"][attributes["POSITION"].get<int>()]["count"].get<std::size_t>();
  EXPECT_GT(n, r.world.vertices.size()) << "split along the seam";
  EXPECT_LT(n, 2 * r.world.vertices.size()) << "and only there";
  // Every copy has the joints and weights of the vertex at its position.
  const auto pos = accessor_data<float>(*bytes, doc, attributes["POSITION"], 3);
  const auto joints = accessor_data<std::uint16_t>(*bytes, doc, attributes["JOINTS_0"], 4);
  const auto weights = accessor_data<float>(*bytes, doc, attributes["WEIGHTS_0"], 4);
  ASSERT_EQ(pos.size(), 3 * n);
  std::size_t matched = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3f p(pos[3 * i], pos[3 * i + 1], pos[3 * i + 2]);
    for (std::size_t v = 0; v < r.scene.vertices.size(); ++v) {
      if ((r.scene.vertices[v] - p).norm() > 1e-5f) continue;
      float strongest = 0.0f;
      std::uint16_t joint = 0;
      for (std::size_t k = 0; k < r.skin.weights[v].size(); ++k)
        if (r.skin.weights[v][k] > strongest) strongest = r.skin.weights[v][k], joint = r.skin.joints[v][k];
      float got = 0.0f;
      for (std::size_t k = 0; k < 4; ++k)
        if (joints[4 * i + k] == joint) got += weights[4 * i + k];
      EXPECT_NEAR(got, strongest, 1e-4f) << i;
      ++matched;
      break;
    }
  }
  EXPECT_EQ(matched, n);
}

TEST(RiggedGlb, NormalisesWeightsForTheValidatorAndMergesRepeatedJoints) {
  const MeshTransform t;
  Rig r = bar_rig(t);
  auto jo = r.skin.joints;
  auto we = r.skin.weights;
  jo[0] = {1, 1, 0, 0}, we[0] = {0.3f, 0.2f, 0.0f, 0.0f};      // repeated joint, sum 0.5
  jo[1] = {0, 1, 1, 0}, we[1] = {0.1f, 0.7f, 0.0f, 0.0f};      // a zero weight on joint 1
  we[2] = {0.3333333f, 0.3333333f, 0.3333333f, 0.0f}, jo[2] = {0, 1, 1, 0};
  auto bytes = encode_rigged_glb(r.world, jo, we, r.skin, t, Vec3f::Ones());
  ASSERT_TRUE(bytes.has_value()) << bytes.error().message;
  const json doc = glb_json(*bytes);
  const json& attr = doc["meshes"][0]["primitives"][0]["attributes"];
  const auto w = accessor_data<float>(*bytes, doc, attr["WEIGHTS_0"].get<int>(), 4);
  const auto j = accessor_data<std::uint16_t>(*bytes, doc, attr["JOINTS_0"].get<int>(), 4);
  EXPECT_EQ(j[0], 1);
  EXPECT_FLOAT_EQ(w[0], 1.0f);
  EXPECT_EQ(w[1], 0.0f);
  EXPECT_EQ(j[1], 0);  // a zero weight names joint 0
  EXPECT_NEAR(w[4 + 1], 0.875f, 1e-6f);
  EXPECT_EQ(j[4 + 2], 0);  // zero weight
  EXPECT_NEAR(w[8 + 1], 2.0f / 3.0f, 1e-6f);  // joint 1 twice, merged
  for (std::size_t v = 0; v < r.world.vertices.size(); ++v) {
    float sum = 0.0f;  // in float, in slot order, as the validator sums
    for (int k = 0; k < 4; ++k) sum += w[4 * v + k];
    EXPECT_LE(std::abs(sum - 1.0f), 2e-7f) << v;
  }
}

TEST(RiggedGlb, BadInputIsAOneLineError) {
  const MeshTransform t;
  const Rig r = bar_rig(t);
  auto check = [&](Result<std::vector<std::uint8_t>> res, const std::string& needle) {
    ASSERT_FALSE(res.has_value()) << needle;
    EXPECT_EQ(res.error().kind, Error::Kind::Input) << res.error().message;
    EXPECT_NE(res.error().message.find(needle), std::string::npos) << res.error().message;
    EXPECT_EQ(res.error().message.find('\n'), std::string::npos) << res.error().message;
  };
  auto jo = r.skin.joints;
  auto we = r.skin.weights;
  jo.pop_back();
  check(encode_rigged_glb(r.world, jo, we, r.skin, t, Vec3f::Ones()), "joint sets");
  jo = r.skin.joints, jo[3] = {7, 0, 0, 0};
  check(encode_rigged_glb(r.world, jo, we, r.skin, t, Vec3f::Ones()), "joint 7 of 2");
  jo = r.skin.joints, we[5][0] = std::nanf("");
  check(encode_rigged_glb(r.world, jo, we, r.skin, t, Vec3f::Ones()), "vertex 5 has weight nan");
  we = r.skin.weights, we[5] = {0, 0, 0, 0};
  check(encode_rigged_glb(r.world, jo, we, r.skin, t, Vec3f::Ones()), "no weight");
  we = r.skin.weights;
  TriangleMesh bad = r.world;
  bad.vertices[2].y() = INFINITY;
  check(encode_rigged_glb(bad, jo, we, r.skin, t, Vec3f::Ones()), "non-finite vertex");
  MeshTransform zero;
  zero.scale.y() = 0.0f;
  check(encode_rigged_glb(r.world, jo, we, r.skin, zero, Vec3f::Ones()), "scale");
  Skin skin = r.skin;
  skin.clips[0].channels[1].rotation_times = {0.0, 0.7, 0.5};
  check(encode_rigged_glb(r.world, jo, we, skin, t, Vec3f::Ones()), "decreasing key times");
  skin = r.skin, skin.joint_nodes[1] = 9;
  check(encode_rigged_glb(r.world, jo, we, skin, t, Vec3f::Ones()), "refers to node 9");
  skin = r.skin, skin.inverse_bind.pop_back();
  check(encode_rigged_glb(r.world, jo, we, skin, t, Vec3f::Ones()), "inverse bind");
  // The file system's refusal is an Io error naming the path.
  const Status s = write_rigged_glb("/proc/nonexistent/rigged.glb", r.world, jo, we, r.skin, t, Vec3f::Ones());
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.error().kind, Error::Kind::Io) << s.error().message;
  EXPECT_NE(s.error().message.find("rigged.glb"), std::string::npos) << s.error().message;
}

TEST(RiggedGlb, KeysOutsideTheClipAreCutWhereThePoseClampsThem) {
  const MeshTransform t;
  const Rig r = bar_rig(t);
  Skin skin = r.skin;
  // Keys before 0 and after the 1 s duration: the file holds the values the C++ pose shows at 0 and at 1 s.
  skin.clips[0].channels[0].translation_times = {-1.0, 3.0};
  skin.clips[0].channels[0].translations = {Vec3f::Zero(), Vec3f(0.4f, 0.0f, 0.0f)};
  auto bytes = encode_rigged_glb(r.world, r.skin.joints, r.skin.weights, skin, t, Vec3f::Ones());
  ASSERT_TRUE(bytes.has_value()) << bytes.error().message;
  const json doc = glb_json(*bytes);
  const json& sampler = doc["animations"][0]["samplers"][0];
  const auto times = accessor_data<float>(*bytes, doc, sampler["input"].get<int>(), 1);
  const auto values = accessor_data<float>(*bytes, doc, sampler["output"].get<int>(), 3);
  ASSERT_EQ(times.size(), 2u);
  EXPECT_FLOAT_EQ(times[0], 0.0f);
  EXPECT_FLOAT_EQ(times[1], 1.0f);
  EXPECT_NEAR(values[0], 0.1f, 1e-6f);  // a quarter of the way from −1 s to 3 s
  EXPECT_NEAR(values[3], 0.2f, 1e-6f);
}

// The Khronos validator and three.js (npm packages of scripts/setup) on the bar under each T: 0 errors, one skinned
// mesh with two bones, both clips, and at three times of each clip the skinned vertices' bounds are the C++ pose's.
TEST(RiggedGlb, PassesTheValidatorAndThreeJsPlaysTheCppPose) {
  if (test::shell("node --version").first != 0) GTEST_SKIP() << "node is not installed (scripts/setup installs it)";
  ASSERT_TRUE(std::filesystem::exists(test::source_dir() / "node_modules" / "gltf-validator"))
      << "npm packages missing: run scripts/setup";
  const auto dir = test::temp_dir("rigged");
  const auto script = test::source_dir() / "scripts" / "check_rigged_glb.mjs";
  int k = 0;
  for (const MeshTransform& t : test::rig_transforms()) {
    SCOPED_TRACE("transform " + std::to_string(k));
    const Rig r = bar_rig(t);
    const auto path = dir / ("bar" + std::to_string(k++) + ".glb");
    ASSERT_TRUE(write_rigged_glb(path, r.world, r.skin.joints, r.skin.weights, r.skin, t, Vec3f(0.2f, 0.5f, 0.8f)).ok());
    struct Play {
      const char* clip;
      int index;
      std::vector<double> times;
    };
    for (const Play& play : {Play{"bend", 0, {0.25, 0.5, 1.0}}, Play{"wave", 1, {0.5, 1.0, 1.7}}}) {
      std::string times;
      for (double x : play.times) {
        if (!times.empty()) times += ',';
        times += std::to_string(x);
      }
      const auto [rc, out] = test::shell("node '" + script.string() + "' '" + path.string() + "' --clip " + play.clip +
                                         " --times " + times);
      ASSERT_EQ(rc, 0) << out;
      const json j = json::parse(out.substr(out.rfind("\n{") == std::string::npos ? 0 : out.rfind("\n{") + 1), nullptr, false);
      ASSERT_FALSE(j.is_discarded()) << out;
      EXPECT_EQ(j["errors"], 0) << out;
      EXPECT_EQ(j["three"]["skinned_meshes"], 1) << out;
      EXPECT_EQ(j["three"]["bones"], 2) << out;
      EXPECT_EQ(j["three"]["vertices"], r.world.vertices.size()) << out;
      ASSERT_EQ(j["three"]["clips"].size(), 2u) << out;
      EXPECT_NEAR(j["three"]["clips"][0]["duration"].get<double>(), 1.0, 1e-6) << out;
      EXPECT_NEAR(j["three"]["clips"][1]["duration"].get<double>(), 2.0, 1e-6) << out;
      EXPECT_EQ(j["three"]["clip"], play.clip) << out;
      ASSERT_EQ(j["three"]["poses"].size(), play.times.size()) << out;
      for (std::size_t i = 0; i < play.times.size(); ++i) {
        const Aabb want = test::bounds_of(
            test::pose_world(r.world, r.skin.joints, r.skin.weights, r.skin, t, play.index, play.times[i]));
        const double tol = 1e-3 * want.size().norm();
        const json& pose = j["three"]["poses"][i];
        for (int a = 0; a < 3; ++a) {
          EXPECT_NEAR(pose["min"][a].get<double>(), want.min[a], tol) << play.clip << " t=" << play.times[i] << " " << out;
          EXPECT_NEAR(pose["max"][a].get<double>(), want.max[a], tol) << play.clip << " t=" << play.times[i] << " " << out;
        }
      }
    }
  }
}

}  // namespace
}  // namespace ff::io
