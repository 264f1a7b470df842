// The liquid's look (pipeline/liquid_look.h): each vertex takes the colour of its own target (the duck's texture at
// the nearest point of the duck, a tinted target's tint, white for water), free fluid the nearest look, and a moving
// target is asked in its rest frame.
#include "pipeline/liquid_look.h"
#include "sampling/mesh_field.h"
#include "io/write_mesh.h"
#include "support/shapes.h"
#include "support/test_support.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>

namespace ff::pipeline {
namespace {
namespace fs = std::filesystem;

const fs::path kDuck = "/usr/share/assimp/models/Collada/duck.dae";

// The duck's look colour at its own vertex v (of triangle t, corner c).
struct DuckPoint {
  Vec3f position, colour;
};
std::vector<DuckPoint> duck_points(const io::TargetLook& look, std::size_t count) {
  std::vector<DuckPoint> out;
  const std::size_t step = std::max<std::size_t>(1, look.mesh.triangles.size() / count);
  for (Index t = 0; t < look.mesh.triangles.size(); t += Index(step)) {
    const auto& tri = look.mesh.triangles[t];
    const Vec3f bary = Vec3f::Constant(1.0f / 3.0f);
    out.push_back({(look.mesh.vertices[tri[0]] + look.mesh.vertices[tri[1]] + look.mesh.vertices[tri[2]]) / 3.0f,
                   look.colour_at(t, bary)});
  }
  return out;
}

scene::Scene two_targets(const fs::path& dir) {
  scene::Scene s;
  s.targets.resize(3);
  s.targets[0].mesh = kDuck;
  s.targets[0].appearance = scene::Appearance::Target;
  EXPECT_TRUE(io::write_obj(dir / "ball.obj", test::uv_sphere(0.3f, 16)).ok());
  s.targets[1].mesh = dir / "ball.obj";
  s.targets[1].transform.translate = Vec3f(5.0f, 0.0f, 0.0f);
  s.targets[1].appearance = scene::Appearance::Tint;
  s.targets[1].tint = Vec3f(0.9f, 0.1f, 0.1f);
  s.targets[2].mesh = dir / "ball.obj";
  s.targets[2].transform.translate = Vec3f(-5.0f, 0.0f, 0.0f);  // water
  return s;
}

TEST(LiquidLook, EachVertexTakesItsOwnTargetsLook) {
  ASSERT_TRUE(fs::exists(kDuck)) << "install assimp-testmodels (scripts/setup)";
  const fs::path dir = test::temp_dir("liquid-look");
  const scene::Scene s = two_targets(dir);
  const LiquidLooks looks = load_liquid_looks(s, {}, {});
  EXPECT_TRUE(looks.warnings.empty());
  ASSERT_TRUE(looks.coloured());
  const auto materials = looks.materials();
  ASSERT_EQ(materials.size(), 3u);
  EXPECT_TRUE(materials[0].coloured && materials[1].coloured && !materials[2].coloured);

  auto look = io::load_target_look(kDuck);
  ASSERT_TRUE(look.has_value());
  const auto points = duck_points(*look, 200);
  io::TriangleMesh mesh;
  std::vector<std::uint8_t> labels;
  for (const auto& p : points) mesh.vertices.push_back(p.position), labels.push_back(0);
  for (const auto& p : points) mesh.vertices.push_back(p.position), labels.push_back(255);  // free fluid: nearest look
  mesh.vertices.push_back(Vec3f(5.0f, 0.3f, 0.0f)), labels.push_back(1);
  mesh.vertices.push_back(Vec3f(-5.0f, 0.3f, 0.0f)), labels.push_back(2);
  const auto colours = liquid_colours(looks, mesh, labels, 0.0);
  ASSERT_EQ(colours.size(), mesh.vertices.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    EXPECT_TRUE(colours[i].isApprox(points[i].colour, 1e-3f)) << i;
    EXPECT_TRUE(colours[points.size() + i].isApprox(points[i].colour, 1e-3f)) << i;
  }
  EXPECT_TRUE(colours[2 * points.size()].isApprox(Vec3f(0.9f, 0.1f, 0.1f)));
  EXPECT_TRUE(colours[2 * points.size() + 1].isApprox(Vec3f::Ones())) << "water stays white (its material decides)";
}

TEST(LiquidLook, AMovingTargetIsAskedInItsRestFrame) {
  scene::Scene s;
  s.targets.resize(1);
  s.targets[0].mesh = kDuck;
  s.targets[0].appearance = scene::Appearance::Target;
  pose::TargetMotion motion;
  motion.keys = {pose::Keyframe{0.0, Vec3f(0.0f, 0.0f, 0.0f)}, pose::Keyframe{1.0, Vec3f(3.0f, 0.0f, 0.0f)}};
  const LiquidLooks looks = load_liquid_looks(s, {}, {motion});
  auto look = io::load_target_look(kDuck);
  ASSERT_TRUE(look.has_value());
  const auto points = duck_points(*look, 100);
  io::TriangleMesh moved;
  for (const auto& p : points) moved.vertices.push_back(p.position + Vec3f(3.0f, 0.0f, 0.0f));
  const auto at_end = liquid_colours(looks, moved, {}, 1.0);
  std::size_t same = 0;
  for (std::size_t i = 0; i < points.size(); ++i) same += at_end[i].isApprox(points[i].colour, 1e-3f);
  EXPECT_EQ(same, points.size());
  // At the start the duck is still at rest: the same points, 3 m away, find only its nearest side.
  const auto at_start = liquid_colours(looks, moved, {}, 0.0);
  std::size_t still = 0;
  for (std::size_t i = 0; i < points.size(); ++i) still += at_start[i].isApprox(points[i].colour, 1e-3f);
  EXPECT_LT(still, points.size());
}

TEST(LiquidLook, WaterOnlyScenesAreNotColouredAndAnUnreadableLookFallsBackToTheTint) {
  scene::Scene s;
  s.targets.resize(1);
  s.targets[0].mesh = kDuck;
  EXPECT_FALSE(load_liquid_looks(s, {}, {}).coloured());
  s.targets[0].mesh = "/nonexistent/duck.dae";
  s.targets[0].appearance = scene::Appearance::Target;
  const LiquidLooks looks = load_liquid_looks(s, {}, {});
  ASSERT_EQ(looks.warnings.size(), 1u);
  EXPECT_NE(looks.warnings[0].find("tint"), std::string::npos) << looks.warnings[0];
  io::TriangleMesh m;
  m.vertices = {Vec3f::Zero()};
  EXPECT_TRUE(liquid_colours(looks, m, {}, 0.0)[0].isApprox(s.targets[0].tint));
}

const fs::path kEarth = "/usr/share/assimp/models/Collada/earthCylindrical.DAE";

// A world map finer than the formed mesh (earthCylindrical.DAE: a 2048×1024 photograph on a sphere of 1 920
// triangles): a sphere of ~1 100 vertices over it gets UVs; no triangle's UVs sweep across the map (the map's wrap
// seam and its poles are handled); and the UVs keep clearly more of the map than vertex colours (measure_look).
// Several targets in a scene: vertex colours only.
TEST(LiquidLook, UvsIntoAFineTextureKeepMoreThanVertexColours) {
  ASSERT_TRUE(fs::exists(kEarth)) << "install assimp-testmodels (scripts/setup)";
  scene::Scene s;
  s.targets.resize(1);
  s.targets[0].mesh = kEarth;
  s.targets[0].appearance = scene::Appearance::Target;
  const LiquidLooks looks = load_liquid_looks(s, {}, {});
  ASSERT_NE(looks.targets[0].texture, nullptr);
  EXPECT_EQ(looks.targets[0].texture->image.width, 2048);
  auto look = io::load_target_look(kEarth);
  ASSERT_TRUE(look.has_value());
  // The formed mesh: a sphere of its own triangulation laid on the map's surface (each vertex moved to its nearest
  // point of the target), as a formed liquid lies on it.
  Vec3f centre = Vec3f::Zero();
  for (const Vec3f& v : look->mesh.vertices) centre += v / float(look->mesh.vertices.size());
  auto field = sampling::MeshField::build(look->mesh);
  ASSERT_TRUE(field.has_value());
  io::TriangleMesh mesh = test::uv_sphere(1.0f, 48);
  for (Vec3f& v : mesh.vertices) v = field->closest(centre + v).point;
  mesh.colours = liquid_colours(looks, mesh, {}, 0.0);
  mesh.corner_uv = liquid_uvs(looks, mesh, 0.0);
  ASSERT_EQ(mesh.corner_uv.size(), mesh.triangles.size());
  mesh.texture = looks.targets[0].texture;
  float widest = 0.0f;
  for (const auto& uv : mesh.corner_uv) {
    const auto [lo, hi] = std::minmax({uv[0].x(), uv[1].x(), uv[2].x()});
    widest = std::max(widest, hi - lo);
  }
  float target_widest = 0.0f;  // the map's own triangles: some of earthCylindrical's span half of it
  for (const auto& t : look->mesh.triangles) {
    const auto [lo, hi] = std::minmax({look->uv[t[0]].x(), look->uv[t[1]].x(), look->uv[t[2]].x()});
    target_widest = std::max(target_widest, hi - lo);
  }
  const LookMeasure m = measure_look(looks, mesh, 0.0);
  std::printf("earth, %zu vertices: UVs %.2f, vertex colours %.2f sRGB steps (%zu points); widest triangle in u %.3f "
              "(the map's own: %.3f)\n", mesh.vertices.size(), m.uvs, m.vertex_colours, m.points, widest, target_widest);
  EXPECT_LE(widest, target_widest + 0.1f) << "a triangle sweeps across the map";
  EXPECT_EQ(m.points, 20000u);
  EXPECT_TRUE(m.uvs_win());
  EXPECT_LT(m.uvs, 0.5 * m.vertex_colours);

  const fs::path dir = test::temp_dir("liquid-look-uv");
  const LiquidLooks several = load_liquid_looks(two_targets(dir), {}, {});
  EXPECT_EQ(several.targets[0].texture, nullptr);
  EXPECT_TRUE(liquid_uvs(several, mesh, 0.0).empty());
}

}  // namespace
}  // namespace ff::pipeline
