// The wall thickness along the inward normal (sampling/thickness.h) on shapes whose thinnest wall is known.
#include "sampling/thickness.h"

#include "io/load_mesh.h"

#include "support/shapes.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

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

// The hard-target families of bench_scenes (issue 44): each shape closed, outward, of the volume its definition
// gives, and its thinnest part read as its wall, its pipe wall, or its gear's disc.
TEST(Thickness, TheHardFamiliesAreClosedAndTheirWallsRead) {
  const float wall = 0.037f;
  const io::TriangleMesh bin = test::open_box(Vec3f(0.5f, 0.35f, 0.4f), wall);
  auto bin_field = MeshField::build(bin);
  ASSERT_TRUE(bin_field.has_value());
  EXPECT_TRUE(bin_field->inside(Vec3f(0.5f - 0.5f * wall, 0.0f, 0.0f))) << "in a wall";
  EXPECT_TRUE(bin_field->inside(Vec3f(0.0f, -0.35f + 0.5f * wall, 0.0f))) << "in the floor";
  EXPECT_FALSE(bin_field->inside(Vec3f(0.0f, 0.0f, 0.0f))) << "in the bin";
  // volume() sums its parts (overlaps twice): the floor, two walls across x and two across z.
  const double slabs = 1.0 * 0.8 * wall + 2.0 * (wall * 0.7 * 0.8) + 2.0 * (1.0 * 0.7 * wall);
  EXPECT_NEAR(bin_field->volume(), slabs, 1e-3 * slabs);
  EXPECT_NEAR(measure(bin).thinnest, wall, 0.1f * wall);

  const float r = 0.3f, w = 0.025f;
  const io::TriangleMesh pipe = test::pipe(r, w, 1.0f, 64);
  const double polygon = 0.5 * 64 * std::sin(2.0 * std::numbers::pi / 64);  // area of the 64-gon of radius 1
  EXPECT_NEAR(io::signed_volume(pipe), polygon * (r * r - (r - w) * (r - w)), 1e-4);
  EXPECT_NEAR(measure(pipe).thinnest, w, 0.1f * w);

  const io::TriangleMesh gear = test::gear(24, 0.4f, 0.5f, 0.03f);
  EXPECT_GT(io::signed_volume(gear), std::numbers::pi * 0.4 * 0.4 * 0.03);
  EXPECT_LT(io::signed_volume(gear), std::numbers::pi * 0.5 * 0.5 * 0.03);
  // Its teeth are thinner than the disc: an eighth of the pitch at the tip (1.6 cm), a quarter at the root (2.6 cm).
  const float tooth = measure(gear).thinnest;
  EXPECT_GT(tooth, 0.015f);
  EXPECT_LT(tooth, 0.027f);

  const io::TriangleMesh parts = test::overlapping_parts();
  auto field = MeshField::build(parts);
  ASSERT_TRUE(field.has_value());
  EXPECT_TRUE(field->encloses_volume());
  EXPECT_TRUE(field->inside(Vec3f(0.22f, 0.45f, 0.0f))) << "in the ball, above the box";
  EXPECT_TRUE(field->inside(Vec3f(0.0f, 0.45f, -0.3f))) << "in the gear, above the box";
  EXPECT_TRUE(field->inside(Vec3f(0.0f, 0.33f, 0.0f))) << "in the torus's tube, above the box";
  EXPECT_FALSE(field->inside(Vec3f(-0.2f, 0.33f, 0.0f))) << "in the torus's hole, above the box";
}

}  // namespace
}  // namespace ff::sampling
