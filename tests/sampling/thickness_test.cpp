// The wall thickness along the inward normal (sampling/thickness.h) on shapes whose thinnest wall is known.
#include "sampling/thickness.h"

#include "support/shapes.h"

#include <gtest/gtest.h>

namespace ff::sampling {
namespace {

Thickness measure(const io::TriangleMesh& mesh) {
  auto field = MeshField::build(mesh);
  EXPECT_TRUE(field.has_value());
  const auto th = measure_thickness(*field, mesh);
  EXPECT_TRUE(th.has_value());
  return th.value_or(Thickness{});
}

TEST(Thickness, ASphereIsItsDiameterThick) {
  const Thickness th = measure(test::uv_sphere(0.5f, 48));
  EXPECT_NEAR(th.thinnest, 1.0f, 0.03f);
  EXPECT_NEAR(th.median, 1.0f, 0.02f);
}

TEST(Thickness, AThinSlabIsItsThickness) {
  // 1 m × 1 m × 2 cm: 2 cm through the slab from both big faces, 1 m across from the rim (4 % of the area)
  const Thickness th = measure(test::box(Vec3f(0.5f, 0.01f, 0.5f), 8));
  EXPECT_NEAR(th.thinnest, 0.02f, 0.002f);
  EXPECT_NEAR(th.median, 0.02f, 0.001f);
  EXPECT_GT(th.thin_area_share, 0.9);
}

TEST(Thickness, TheThinPartOfAShapeIsFoundAndPlaced) {
  // A 0.6 m cube with a 3 cm thin fin sticking out along +x (overlapping it by 1 cm, as parts of a CAD file do): the
  // fin is a small share of the area, but the 2nd percentile of the walls is in it.
  const io::TriangleMesh cube = test::box(Vec3f(0.3f, 0.3f, 0.3f), 4);
  const io::TriangleMesh fin = test::translate(test::box(Vec3f(0.3f, 0.015f, 0.2f), 4), Vec3f(0.59f, 0.0f, 0.0f));
  const Thickness th = measure(test::merge(cube, fin));
  EXPECT_NEAR(th.thinnest, 0.03f, 0.004f);
  EXPECT_GT(th.where.x(), 0.28f) << "on the fin";
  EXPECT_GT(th.median, 0.3f) << "most of the surface is the cube's";
}

TEST(Thickness, AThinVaseWallAndAnOpenSheet) {
  const Thickness vase = measure(test::vase(1.0f, 0.35f, 0.04f));
  EXPECT_NEAR(vase.thinnest, 0.04f, 0.008f);
  // A flat sheet has no inside: no ray from it lands on a far side.
  const io::TriangleMesh sheet = test::plane_sheet(8);
  auto field = MeshField::build(sheet);
  ASSERT_TRUE(field.has_value());
  EXPECT_FALSE(measure_thickness(*field, sheet).has_value());
}

TEST(Thickness, AWedgeIsNoWall) {
  // A regular tetrahedron: near an edge the inward ray leaves through the neighbouring face, 109.5° away (a wedge,
  // not a wall), and from mid-face it leaves through another face the same way: no walls at all.
  io::TriangleMesh tetra;
  tetra.vertices = {{1, 1, 1}, {1, -1, -1}, {-1, 1, -1}, {-1, -1, 1}};
  tetra.triangles = {{0, 1, 2}, {0, 3, 1}, {0, 2, 3}, {1, 3, 2}};
  auto field = MeshField::build(tetra);
  ASSERT_TRUE(field.has_value());
  EXPECT_FALSE(measure_thickness(*field, tetra).has_value());
  // A right tetrahedron's slanted face meets the others at 54.7°: a wedge, not a blade.
  io::TriangleMesh right;
  right.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  right.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  auto right_field = MeshField::build(right);
  ASSERT_TRUE(right_field.has_value());
  EXPECT_FALSE(measure_thickness(*right_field, right).has_value());
}

}  // namespace
}  // namespace ff::sampling
