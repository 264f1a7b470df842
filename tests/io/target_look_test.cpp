// A target's look (io/target_look.h): the duck's texture through its UVs, vertex colours, the material colour when a
// texture cannot be used (a warning, never an error), the scene transform, and the sRGB transfer function.
#include "io/target_look.h"
#include "support/test_support.h"

#include <gtest/gtest.h>

#include <fstream>

namespace ff::io {
namespace {
namespace fs = std::filesystem;

const fs::path kDuck = "/usr/share/assimp/models/Collada/duck.dae";

// The mean colour over every triangle's centre, linear RGB.
Vec3f mean_colour(const TargetLook& look) {
  Vec3f sum = Vec3f::Zero();
  for (Index t = 0; t < look.mesh.triangles.size(); ++t) sum += look.colour_at(t, Vec3f::Constant(1.0f / 3.0f));
  return sum / float(look.mesh.triangles.size());
}

TEST(TargetLook, TheDuckWearsItsTextureThroughItsUVs) {
  ASSERT_TRUE(fs::exists(kDuck)) << "install assimp-testmodels (scripts/setup)";
  auto look = load_target_look(kDuck);
  ASSERT_TRUE(look.has_value()) << look.error().message;
  EXPECT_TRUE(look->warnings.empty()) << look->warnings.front();
  ASSERT_EQ(look->textures.size(), 1u);
  EXPECT_GT(look->textures[0].width, 16);
  EXPECT_EQ(look->textures[0].rgb.size(), std::size_t(look->textures[0].width) * look->textures[0].height * 3);
  ASSERT_EQ(look->uv.size(), look->mesh.vertices.size());
  EXPECT_EQ(look->material.size(), look->mesh.triangles.size());
  EXPECT_TRUE(look->textured());
  // A yellow duck: red and green high, blue low, on average over its surface.
  const Vec3f m = mean_colour(*look);
  EXPECT_GT(m.x(), 0.5f);
  EXPECT_GT(m.y(), 0.3f);
  EXPECT_LT(m.z(), 0.15f);
  // Not one colour: the beak (orange) and the eyes (black) differ from the body.
  float lo = 1.0f, hi = 0.0f;
  for (Index t = 0; t < look->mesh.triangles.size(); ++t) {
    const float g = look->colour_at(t, Vec3f::Constant(1.0f / 3.0f)).y();
    lo = std::min(lo, g), hi = std::max(hi, g);
  }
  EXPECT_GT(hi - lo, 0.4f);
}

TEST(TargetLook, TheSceneTransformIsApplied) {
  auto plain = load_target_look(kDuck);
  MeshTransform t;
  t.scale = Vec3f::Constant(2.0f);
  t.translate = Vec3f(1.0f, 0.0f, 0.0f);
  auto moved = load_target_look(kDuck, t);
  ASSERT_TRUE(plain.has_value() && moved.has_value());
  const Aabb a = plain->mesh.bounds(), b = moved->mesh.bounds();
  EXPECT_NEAR(b.max.x(), 2.0f * a.max.x() + 1.0f, 1e-3f * std::abs(b.max.x()) + 1e-5f);
  EXPECT_NEAR(b.size().y(), 2.0f * a.size().y(), 1e-3f * b.size().y());
}

// The duck's file in a folder of its own, with `texture` as its duckCM.tga (nothing: no texture file).
fs::path lone_duck(const std::string& name, const std::string* texture) {
  const fs::path dir = test::temp_dir(name);
  fs::copy_file(kDuck, dir / "duck.dae", fs::copy_options::overwrite_existing);
  if (texture != nullptr) std::ofstream(dir / "duckCM.tga", std::ios::binary) << *texture;
  return dir / "duck.dae";
}

TEST(TargetLook, AMissingTextureWarnsAndTheMaterialColourIsUsed) {
  auto look = load_target_look(lone_duck("look-missing", nullptr));
  ASSERT_TRUE(look.has_value()) << look.error().message;
  ASSERT_EQ(look->warnings.size(), 1u);
  EXPECT_NE(look->warnings[0].find("duckCM.tga"), std::string::npos) << look->warnings[0];
  EXPECT_NE(look->warnings[0].find("material colour"), std::string::npos) << look->warnings[0];
  EXPECT_TRUE(look->textures.empty());
  // Every point is its material's colour.
  const Vec3f c = look->colour_at(0, Vec3f(0.2f, 0.3f, 0.5f));
  EXPECT_TRUE(c.isApprox(look->materials[look->material[0]].colour));
}

TEST(TargetLook, ABrokenTextureWarnsAndTheMaterialColourIsUsed) {
  const std::string garbage(3000, '\x5a');
  auto look = load_target_look(lone_duck("look-broken", &garbage));
  ASSERT_TRUE(look.has_value()) << look.error().message;
  ASSERT_EQ(look->warnings.size(), 1u);
  EXPECT_NE(look->warnings[0].find("duckCM.tga"), std::string::npos) << look->warnings[0];
  EXPECT_TRUE(look->textures.empty());
}

TEST(TargetLook, VertexColoursAreInterpolated) {
  // A PLY tetrahedron with a red, a green, a blue and a grey corner (PLY colours are sRGB: 128 is 0.2158 linear).
  const fs::path dir = test::temp_dir("look-ply");
  std::ofstream(dir / "tet.ply") << "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
                                    "property float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n"
                                    "element face 4\nproperty list uchar int vertex_indices\nend_header\n"
                                    "0 0 0 255 0 0\n1 0 0 0 255 0\n0 1 0 0 0 255\n0 0 1 128 128 128\n"
                                    "3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n";
  auto look = load_target_look(dir / "tet.ply");
  ASSERT_TRUE(look.has_value()) << look.error().message;
  ASSERT_EQ(look->colours.size(), look->mesh.vertices.size());
  EXPECT_TRUE(look->textured());
  for (Index t = 0; t < look->mesh.triangles.size(); ++t)
    for (int c = 0; c < 3; ++c) {
      const Vec3f& p = look->mesh.vertices[look->mesh.triangles[t][c]];
      const Vec3f want = p == Vec3f(0, 0, 0)   ? Vec3f(1, 0, 0)
                         : p == Vec3f(1, 0, 0) ? Vec3f(0, 1, 0)
                         : p == Vec3f(0, 1, 0) ? Vec3f(0, 0, 1)
                                               : Vec3f::Constant(0.2158f);
      EXPECT_TRUE(look->colour_at(t, Vec3f::Unit(c)).isApprox(want, 1e-3f)) << t << " " << c;
    }
}

TEST(TargetLook, AMissingMeshIsAnErrorNamingIt) {
  auto look = load_target_look("/nonexistent/duck.dae");
  ASSERT_FALSE(look.has_value());
  EXPECT_NE(look.error().message.find("duck.dae"), std::string::npos);
}

TEST(TargetLook, SrgbRoundTrips) {
  for (int c = 0; c < 256; ++c) EXPECT_EQ(linear_to_srgb(srgb_to_linear(std::uint8_t(c))), c);
  EXPECT_FLOAT_EQ(srgb_to_linear(0), 0.0f);
  EXPECT_FLOAT_EQ(srgb_to_linear(255), 1.0f);
  EXPECT_NEAR(srgb_to_linear(188), 0.5f, 0.01f);
}

}  // namespace
}  // namespace ff::io
