#include "io/write_mesh.h"

#include "io/load_mesh.h"
#include "io/picture.h"
#include "support/shapes.h"
#include "support/test_support.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <nlohmann/json.hpp>

#include <cstdio>
#include <cstring>
#include <fstream>
#include <memory>
#include <numbers>
#include <set>
#include <tuple>

namespace ff::io {
namespace {

std::vector<std::uint8_t> read_all(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}

std::uint32_t u32(const std::vector<std::uint8_t>& b, std::size_t at) {
  std::uint32_t v;
  std::memcpy(&v, b.data() + at, 4);
  return v;
}

nlohmann::json glb_json(const std::vector<std::uint8_t>& b) {
  const std::uint32_t len = u32(b, 12);
  return nlohmann::json::parse(b.begin() + 20, b.begin() + 20 + len);
}

// A sequence of frames: a sphere growing and drifting, with an empty frame in the middle.
std::vector<TriangleMesh> frames() {
  std::vector<TriangleMesh> f;
  for (int k = 0; k < 5; ++k) {
    TriangleMesh m = test::uv_sphere(0.2f + 0.05f * float(k), 16 + 4 * k);
    for (auto& v : m.vertices) v += Vec3f(0.1f * float(k), 1.0f, -0.3f);
    f.push_back(k == 2 ? TriangleMesh{} : m);
  }
  return f;
}

TEST(WriteObj, RoundTripsThroughAssimpWithNormals) {
  const auto dir = test::temp_dir("obj");
  const TriangleMesh m = test::torus(0.4f, 0.12f, 32, 12);
  ASSERT_TRUE(write_obj(dir / "t.obj", m).ok());
  auto back = load_mesh(dir / "t.obj");
  ASSERT_TRUE(back.has_value()) << back.error().message;
  ASSERT_EQ(back->triangles.size(), m.triangles.size());
  // The importer may re-index vertices; compare the triangles' corners.
  double worst = 0.0;
  for (std::size_t t = 0; t < m.triangles.size(); ++t)
    for (int c = 0; c < 3; ++c)
      worst = std::max<double>(worst, (back->vertices[back->triangles[t][c]] - m.vertices[m.triangles[t][c]]).norm());
  EXPECT_LT(worst, 1e-6);
  // Normals point away from the tube's centre line (outward), unit length.
  const auto n = vertex_normals(m);
  for (std::size_t i = 0; i < m.vertices.size(); ++i) {
    const Vec3f v = m.vertices[i];
    const Vec3f ring = Vec3f(v.x(), 0.0f, v.z()).normalized() * 0.4f;
    EXPECT_NEAR(n[i].norm(), 1.0f, 1e-5f);
    EXPECT_GT(n[i].dot((v - ring).normalized()), 0.95f) << i;
  }
}

TEST(WriteObj, RejectsAnOutOfRangeIndexAndLeavesNoFile) {
  const auto dir = test::temp_dir("obj");
  TriangleMesh m = test::box(Vec3f(1, 1, 1));
  m.triangles.push_back({0, 1, 99});
  const auto s = write_obj(dir / "bad.obj", m);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.error().message.find("vertex 99"), std::string::npos);
  EXPECT_FALSE(std::filesystem::exists(dir / "bad.obj"));
}

TEST(WriteGlb, LayoutNodesAndStepAnimation) {
  for (const bool quantize : {false, true}) {
    GlbOptions o;
    o.quantize = quantize;
    const auto f = frames();
    auto bytes = encode_glb(f, o);
    ASSERT_TRUE(bytes.has_value()) << bytes.error().message;
    const auto& b = *bytes;
    ASSERT_GE(b.size(), 28u);
    EXPECT_EQ(u32(b, 0), 0x46546C67u);
    EXPECT_EQ(u32(b, 4), 2u);
    EXPECT_EQ(u32(b, 8), b.size());
    EXPECT_EQ(u32(b, 12) % 4, 0u);
    const auto j = glb_json(b);
    EXPECT_EQ(j["meshes"].size(), 4u);  // the empty frame has a node but no mesh
    EXPECT_EQ(j["nodes"][0]["children"].size(), 5u);
    const auto& anim = j["animations"][0];
    ASSERT_EQ(anim["channels"].size(), 5u);
    for (const auto& s : anim["samplers"]) EXPECT_EQ(s["interpolation"], "STEP");
    // Frame 3's visibility keys: 0 until t = 3/60, 1 until 4/60, then 0.
    const auto& acc = j["accessors"];
    const int in = anim["samplers"][3]["input"];
    EXPECT_EQ(acc[in]["count"], 3);
    EXPECT_NEAR(acc[in]["max"][0].get<double>(), 4.0 / 60.0, 1e-6);
    EXPECT_EQ(j.contains("extensionsRequired"), quantize);
  }
}

// The water material: glTF transmission, IOR and volume (absorption sized to the mesh), and the same in the MTL
// that the OBJ names.
TEST(WriteGlb, WaterMaterialWithTransmissionIorAndVolume) {
  GlbOptions o;
  o.material.tint = Vec3f(0.2f, 0.5f, 0.9f);
  const auto f = frames();
  auto bytes = encode_glb(f, o);
  ASSERT_TRUE(bytes.has_value());
  const auto j = glb_json(*bytes);
  ASSERT_EQ(j["materials"].size(), 1u);
  const auto& m = j["materials"][0];
  EXPECT_EQ(m["extensions"]["KHR_materials_transmission"]["transmissionFactor"], 1.0);
  EXPECT_NEAR(m["extensions"]["KHR_materials_ior"]["ior"].get<double>(), 1.33, 1e-6);
  const auto& vol = m["extensions"]["KHR_materials_volume"];
  EXPECT_NEAR(vol["attenuationColor"][2].get<double>(), 0.9, 1e-6);
  EXPECT_GT(vol["attenuationDistance"].get<double>(), 0.0);
  EXPECT_GT(vol["thicknessFactor"].get<double>(), 0.0);
  for (const char* ext : {"KHR_materials_transmission", "KHR_materials_ior", "KHR_materials_volume"})
    EXPECT_NE(std::find(j["extensionsUsed"].begin(), j["extensionsUsed"].end(), ext), j["extensionsUsed"].end()) << ext;
  // A fixed distance is kept as given.
  o.material.attenuation_distance = 0.125f;
  auto bytes2 = encode_glb(f, o);
  ASSERT_TRUE(bytes2.has_value());
  const auto j2 = glb_json(*bytes2);
  EXPECT_NEAR(j2["materials"][0]["extensions"]["KHR_materials_volume"]["attenuationDistance"].get<double>(), 0.125, 1e-6);

  const std::string mtl = encode_mtl(o.material);
  EXPECT_NE(mtl.find("newmtl water\n"), std::string::npos) << mtl;
  EXPECT_NE(mtl.find("Ni 1.330\n"), std::string::npos) << mtl;
  EXPECT_NE(mtl.find("Kd 0.2000 0.5000 0.9000\n"), std::string::npos) << mtl;
  EXPECT_NE(mtl.find("Tf 1 1 1\n"), std::string::npos) << mtl;
  EXPECT_NE(mtl.find("illum 7\n"), std::string::npos) << mtl;
  const std::string obj = encode_obj(f[0], true, "c", "water.mtl");
  const auto at = obj.find("mtllib water.mtl\nusemtl water\n");
  ASSERT_NE(at, std::string::npos);
  EXPECT_LT(at, obj.find("\nf ")) << "before the faces";
  EXPECT_EQ(encode_obj(f[0]).find("mtllib"), std::string::npos);
}

// A sphere in a texture through per-corner UVs, longitude and latitude, with the wrap seam of a world map: a triangle
// across the date line takes u + 1 on its small side, so the vertices there carry two UVs. `distinct`: how many
// (vertex, UV) pairs its corners have, what a writer must split the mesh into.
TriangleMesh textured_sphere(std::size_t& distinct) {
  TriangleMesh m = test::uv_sphere(0.5f, 16);
  auto texture = std::make_shared<MeshTexture>();
  texture->image.width = 4, texture->image.height = 2;
  for (int i = 0; i < 8; ++i) texture->image.rgb.insert(texture->image.rgb.end(), {std::uint8_t(30 * i), 200, std::uint8_t(255 - 30 * i)});
  texture->factor = Vec3f(1.0f, 0.5f, 0.25f);
  m.texture = texture;
  m.colours.assign(m.vertices.size(), Vec3f::Constant(0.5f));
  std::set<std::tuple<Index, float, float>> pairs;
  for (const auto& t : m.triangles) {
    std::array<Vec2f, 3> uv;
    for (int c = 0; c < 3; ++c) {
      const Vec3f& p = m.vertices[t[std::size_t(c)]];
      uv[std::size_t(c)] = Vec2f(std::atan2(p.z(), p.x()) / (2.0f * std::numbers::pi_v<float>) + 0.5f,
                                 std::acos(std::clamp(p.y() / 0.5f, -1.0f, 1.0f)) / std::numbers::pi_v<float>);
    }
    const auto [lo, hi] = std::minmax({uv[0].x(), uv[1].x(), uv[2].x()});
    if (hi - lo > 0.5f)
      for (auto& c : uv)
        if (c.x() < 0.5f) c.x() += 1.0f;
    m.corner_uv.push_back(uv);
    for (int c = 0; c < 3; ++c) pairs.emplace(t[std::size_t(c)], uv[std::size_t(c)].x(), uv[std::size_t(c)].y());
  }
  distinct = pairs.size();
  return m;
}

std::size_t lines_starting(const std::string& text, const std::string& prefix) {
  std::size_t n = 0;
  for (std::size_t at = 0; at < text.size(); at = text.find('\n', at) + 1) {
    if (text.compare(at, prefix.size(), prefix) == 0) ++n;
    if (text.find('\n', at) == std::string::npos) break;
  }
  return n;
}

TEST(WriteObj, ATexturedMeshIsSplitOnlyWhereItsCornersDisagree) {
  std::size_t distinct = 0;
  const TriangleMesh m = textured_sphere(distinct);
  ASSERT_GT(distinct, m.vertices.size()) << "the sphere has a seam";
  const std::string obj = encode_obj(m, true, "c", "water.mtl");
  EXPECT_EQ(lines_starting(obj, "v "), distinct);
  EXPECT_EQ(lines_starting(obj, "vt "), distinct);
  EXPECT_EQ(lines_starting(obj, "vn "), distinct);
  EXPECT_EQ(lines_starting(obj, "f "), m.triangles.size());
  EXPECT_NE(obj.find("usemtl liquid_textured\n"), std::string::npos);
  EXPECT_NE(obj.find("\nf 1/1/1 "), std::string::npos) << obj.substr(obj.find("\nf "), 40);
  const std::string mtl = encode_mtl(WaterMaterial{}, "liquid_texture.png", m.texture->factor);
  EXPECT_NE(mtl.find("newmtl liquid_textured\n"), std::string::npos) << mtl;
  EXPECT_NE(mtl.find("Kd 1.0000 0.5000 0.2500\n"), std::string::npos) << mtl;
  EXPECT_NE(mtl.find("map_Kd liquid_texture.png\n"), std::string::npos) << mtl;
  EXPECT_EQ(encode_mtl(WaterMaterial{}).find("liquid_textured"), std::string::npos);
  // Written and read back (Assimp): the same triangles, split along the seam only.
  const auto dir = test::temp_dir("obj-uv");
  ASSERT_TRUE(write_obj(dir / "t.obj", m).ok());
  auto back = load_mesh(dir / "t.obj");
  ASSERT_TRUE(back.has_value()) << back.error().message;
  EXPECT_EQ(back->triangles.size(), m.triangles.size());
  // UVs that do not fit the mesh are refused, and nothing is written.
  TriangleMesh bad = m;
  bad.corner_uv.pop_back();
  auto st = write_obj(dir / "bad.obj", bad);
  ASSERT_FALSE(st.ok());
  EXPECT_NE(st.error().message.find("UVs for"), std::string::npos) << st.error().message;
  bad = m;
  bad.texture.reset();
  st = write_obj(dir / "bad.obj", bad);
  ASSERT_FALSE(st.ok());
  EXPECT_NE(st.error().message.find("without a texture"), std::string::npos) << st.error().message;
  EXPECT_FALSE(std::filesystem::exists(dir / "bad.obj"));
}

// Two textured frames: TEXCOORD_0 (glTF's v, flipped), no COLOR_0 (glTF would multiply the two), the texture embedded
// once as a PNG that decodes to the same pixels, and a material that shows it times its factor.
TEST(WriteGlb, TexturedFramesCarryTheirUvsAndEmbedTheTextureOnce) {
  std::size_t distinct = 0;
  const TriangleMesh m = textured_sphere(distinct);
  for (const bool quantize : {true, false}) {
    GlbOptions o;
    o.quantize = quantize;
    o.material.coloured = true;
    const std::vector<TriangleMesh> f{m, m};
    auto bytes = encode_glb(f, o);
    ASSERT_TRUE(bytes.has_value()) << bytes.error().message;
    const auto j = glb_json(*bytes);
    ASSERT_EQ(j["images"].size(), 1u);
    ASSERT_EQ(j["textures"].size(), 1u);
    ASSERT_EQ(j["samplers"].size(), 1u);
    EXPECT_EQ(j["samplers"][0]["wrapS"], 10497);
    ASSERT_EQ(j["materials"].size(), 2u);
    const auto& mat = j["materials"][1];
    EXPECT_EQ(mat["pbrMetallicRoughness"]["baseColorTexture"]["index"], 0);
    EXPECT_NEAR(mat["pbrMetallicRoughness"]["baseColorFactor"][1].get<double>(), 0.5, 1e-6);
    for (const auto& mesh : j["meshes"]) {
      const auto& prim = mesh["primitives"][0];
      EXPECT_EQ(prim["material"], 1);
      EXPECT_FALSE(prim["attributes"].contains("COLOR_0"));
      const auto& acc = j["accessors"][prim["attributes"]["TEXCOORD_0"].get<int>()];
      EXPECT_EQ(acc["count"], distinct);
      EXPECT_EQ(j["accessors"][prim["attributes"]["POSITION"].get<int>()]["count"], distinct);
    }
    // The embedded PNG is the texture.
    const std::size_t bin = 20 + u32(*bytes, 12) + 8;
    const auto& view = j["bufferViews"][j["images"][0]["bufferView"].get<int>()];
    const std::size_t at = bin + view.value("byteOffset", std::size_t(0));
    auto png = decode_png(std::span<const std::uint8_t>(bytes->data() + at, view["byteLength"].get<std::size_t>()));
    ASSERT_TRUE(png.has_value());
    EXPECT_EQ(png->width, 4);
    EXPECT_EQ(png->rgb, m.texture->image.rgb);
    // v flipped: the first vertex's TEXCOORD_0 is (u, 1 − v) of the first corner written.
    const auto& uv_acc = j["accessors"][j["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_0"].get<int>()];
    const auto& uv_view = j["bufferViews"][uv_acc["bufferView"].get<int>()];
    float first[2];
    std::memcpy(first, bytes->data() + bin + uv_view.value("byteOffset", std::size_t(0)), 8);
    EXPECT_FLOAT_EQ(first[0], m.corner_uv[0][0].x());
    EXPECT_FLOAT_EQ(first[1], 1.0f - m.corner_uv[0][0].y());
  }
}

TEST(WriteGlb, QuantizedPositionsDecodeWithinAHalfStep) {
  GlbOptions o;
  const auto f = frames();
  auto bytes = encode_glb(f, o);
  ASSERT_TRUE(bytes.has_value());
  const auto j = glb_json(*bytes);
  const std::size_t bin = 20 + u32(*bytes, 12) + 8;
  // Frame 4: its node's child holds the mesh and the dequantization transform.
  const int node = j["nodes"][0]["children"][4];
  const auto& child = j["nodes"][j["nodes"][node]["children"][0].get<int>()];
  const auto& prim = j["meshes"][child["mesh"].get<int>()]["primitives"][0];
  const auto& acc = j["accessors"][prim["attributes"]["POSITION"].get<int>()];
  const auto& view = j["bufferViews"][acc["bufferView"].get<int>()];
  ASSERT_EQ(acc["count"], f[4].vertices.size());
  double worst = 0.0, step = 0.0;
  for (std::size_t i = 0; i < f[4].vertices.size(); ++i)
    for (int a = 0; a < 3; ++a) {
      std::int16_t q;
      std::memcpy(&q, bytes->data() + bin + view["byteOffset"].get<std::size_t>() + 8 * i + 2 * a, 2);
      const double s = child["scale"][a], t = child["translation"][a];
      const double v = t + s * std::max(q / 32767.0, -1.0);
      worst = std::max(worst, std::abs(v - f[4].vertices[i][a]));
      step = std::max(step, s / 32767.0);
    }
  EXPECT_LE(worst, 0.5 * step + 1e-7);
  EXPECT_LT(step, 1e-4);  // 16 bits over a ~0.8 m box
}

TEST(WriteGlb, BadInputIsAClearError) {
  GlbOptions o;
  EXPECT_FALSE(encode_glb({}, o).has_value());
  auto f = frames();
  f[1].vertices[0].x() = NAN;
  auto r = encode_glb(f, o);
  ASSERT_FALSE(r.has_value());
  EXPECT_NE(r.error().message.find("non-finite"), std::string::npos);
  o.fps = 0;
  EXPECT_FALSE(encode_glb(frames(), o).has_value());
}

// The Khronos validator and three.js's GLTFLoader (npm packages installed by scripts/setup) on both encodings.
TEST(WriteGlb, PassesTheKhronosValidatorAndLoadsInThreeJs) {
  const auto dir = test::temp_dir("glb");
  const auto script = test::source_dir() / "scripts" / "check_glb.mjs";
  ASSERT_TRUE(std::filesystem::exists(test::source_dir() / "node_modules" / "gltf-validator"))
      << "npm packages missing: run scripts/setup";
  for (const bool quantize : {false, true}) {
    GlbOptions o;
    o.quantize = quantize;
    const auto f = frames();
    const auto path = dir / (quantize ? "q.glb" : "f.glb");
    ASSERT_TRUE(write_glb(path, f, o).ok());
    const std::string cmd = "node '" + script.string() + "' '" + path.string() + "' 2>&1";
    std::string out;
    FILE* p = ::popen(cmd.c_str(), "r");
    ASSERT_NE(p, nullptr);
    char buf[4096];
    while (std::fgets(buf, sizeof buf, p)) out += buf;
    const int rc = ::pclose(p);
    ASSERT_EQ(rc, 0) << out;
    const auto j = nlohmann::json::parse(out, nullptr, false);
    ASSERT_FALSE(j.is_discarded()) << out;
    EXPECT_EQ(j["errors"], 0) << out;
    EXPECT_EQ(j["three"]["meshes"], 4) << out;
    EXPECT_EQ(j["three"]["clips"], 1) << out;
    EXPECT_NEAR(j["three"]["duration"].get<double>(), 5.0 / 60.0, 1e-4) << out;  // the last frame holds 1/60 s
    // At the end of the clip exactly the last frame shows, where it was written.
    EXPECT_EQ(j["three"]["visible_at_end"], 1) << out;
    EXPECT_EQ(j["three"]["vertices_last"], f[4].vertices.size()) << out;
    const Aabb box = f[4].bounds();
    for (int a = 0; a < 3; ++a) {
      EXPECT_NEAR(j["three"]["box_last"][0][a].get<double>(), box.min[a], 1e-4) << out;
      EXPECT_NEAR(j["three"]["box_last"][1][a].get<double>(), box.max[a], 1e-4) << out;
    }
  }
}

// A liquid with the target's look (appearance tint or target): vertex colours as OBJ `v x y z r g b` (sRGB) naming the
// MTL's opaque "liquid", and as the GLB's COLOR_0 with an opaque material, which the Khronos validator passes and
// three.js shows (the colours three.js reads back are the ones written).
TEST(WriteGlb, VertexColoursInObjAndGlbPassTheValidatorAndShowInThreeJs) {
  auto f = frames();
  for (auto& m : f) {
    m.colours.resize(m.vertices.size());
    for (std::size_t i = 0; i < m.vertices.size(); ++i) m.colours[i] = Vec3f(0.8f, i % 2 ? 0.5f : 0.1f, 0.05f);
  }
  const std::string obj = encode_obj(f[0], true, "c", "water.mtl");
  EXPECT_NE(obj.find("mtllib water.mtl\nusemtl liquid\n"), std::string::npos);
  // 0.8 linear is sRGB 231/255 = 0.9059, 0.1 is 89/255 = 0.3490, 0.05 is 63/255 = 0.2471.
  EXPECT_NE(obj.find(" 0.9059 0.3490 0.2471\n"), std::string::npos) << obj.substr(0, 400);
  const std::string mtl = encode_mtl(WaterMaterial{});
  EXPECT_NE(mtl.find("newmtl liquid\n"), std::string::npos) << mtl;

  const auto dir = test::temp_dir("glb-colours");
  for (const bool quantize : {false, true}) {
    GlbOptions o;
    o.quantize = quantize;
    o.material.coloured = true;
    auto bytes = encode_glb(f, o);
    ASSERT_TRUE(bytes.has_value()) << bytes.error().message;
    const auto j = glb_json(*bytes);
    EXPECT_FALSE(j["materials"][0].contains("extensions")) << "opaque";
    EXPECT_EQ(j["meshes"][0]["primitives"][0]["attributes"].contains("COLOR_0"), true);
    const auto path = dir / (quantize ? "q.glb" : "f.glb");
    ASSERT_TRUE(write_glb(path, f, o).ok());
    const std::string cmd = "node '" + (test::source_dir() / "scripts" / "check_glb.mjs").string() + "' '" + path.string() + "' 2>&1";
    std::string out;
    FILE* p = ::popen(cmd.c_str(), "r");
    ASSERT_NE(p, nullptr);
    char buf[4096];
    while (std::fgets(buf, sizeof buf, p)) out += buf;
    ASSERT_EQ(::pclose(p), 0) << out;
    const auto r = nlohmann::json::parse(out, nullptr, false);
    ASSERT_FALSE(r.is_discarded()) << out;
    EXPECT_EQ(r["errors"], 0) << out;
    EXPECT_EQ(r["warnings"], 0) << out;
    EXPECT_TRUE(r["three"]["vertex_colours"].get<bool>()) << out;
    ASSERT_TRUE(r["three"]["colours_last"].is_array()) << out;
    EXPECT_NEAR(r["three"]["colours_last"][0].get<double>(), 0.8, 0.01) << out;
    EXPECT_NEAR(r["three"]["colours_last"][1].get<double>(), 0.3, 0.02) << out;
    EXPECT_NEAR(r["three"]["colours_last"][2].get<double>(), 0.05, 0.01) << out;
  }
  // Colours that do not match the vertices are an error, not a file.
  f[1].colours.pop_back();
  EXPECT_FALSE(encode_glb(f, GlbOptions{}).has_value());
}

TEST(WritePc2, HeaderAndSamplesAreTheBlenderLayout) {
  const auto dir = test::temp_dir("pc2");
  std::vector<std::vector<Vec3f>> f = {{{0, 1, 2}, {3, 4, 5}}, {{6, 7, 8}, {9, 10, 11}}, {{1, 1, 1}, {2, 2, 2}}};
  ASSERT_TRUE(write_pc2(dir / "p.pc2", f, 1.0f).ok());
  const auto b = read_all(dir / "p.pc2");
  ASSERT_EQ(b.size(), 32u + 3 * 2 * 12);
  EXPECT_EQ(std::string(reinterpret_cast<const char*>(b.data())), "POINTCACHE2");
  EXPECT_EQ(u32(b, 12), 1u);  // version
  EXPECT_EQ(u32(b, 16), 2u);  // points
  float start, rate, last;
  std::memcpy(&start, b.data() + 20, 4);
  std::memcpy(&rate, b.data() + 24, 4);
  EXPECT_EQ(start, 1.0f);
  EXPECT_EQ(rate, 1.0f);
  EXPECT_EQ(u32(b, 28), 3u);  // samples
  std::memcpy(&last, b.data() + b.size() - 4, 4);
  EXPECT_EQ(last, 2.0f);
  f[1].pop_back();
  EXPECT_FALSE(write_pc2(dir / "bad.pc2", f).ok());
  EXPECT_FALSE(std::filesystem::exists(dir / "bad.pc2"));
}

}  // namespace
}  // namespace ff::io
