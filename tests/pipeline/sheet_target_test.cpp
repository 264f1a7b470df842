// An open sheet as a target (glTF2/simple_skin, a cloth, a terrain patch) with the defaults: the scene completion
// sizes its fluid as one particle per surface sample (it has no volume to size it by), and the shape metrics measure
// the fluid against the slab one sample spacing thick that those samples stand for, the same on both sides.
#include "metrics/shape_metrics.h"
#include "pipeline/auto_scene.h"
#include "sampling/samplers.h"

#include "sim/emitter.h"

#include <gtest/gtest.h>

#include <cmath>

namespace ff::pipeline {
namespace {

io::TriangleMesh square_sheet(float size) {
  io::TriangleMesh m;
  m.vertices = {Vec3f(0, 0, 0), Vec3f(size, 0, 0), Vec3f(size, size, 0), Vec3f(0, size, 0)};
  m.triangles = {{0, 1, 2}, {0, 2, 3}};
  return m;
}

std::vector<TargetGeometry> sheet_geometry(float size) {
  TargetGeometry g;
  g.mesh = square_sheet(size);
  auto field = sampling::MeshField::build(g.mesh);
  EXPECT_TRUE(field.has_value());
  EXPECT_FALSE(field->encloses_volume());
  g.area = field->area();
  g.box = field->bounds();
  g.field = std::move(*field);
  std::vector<TargetGeometry> out;
  out.push_back(std::move(g));
  return out;
}

TEST(SheetTarget, TheDefaultsSizeItsFluidAsOneParticlePerSurfaceSample) {
  scene::Scene s;
  s.targets.emplace_back();
  auto geometry = sheet_geometry(1.0f);
  const Status done = complete_scene(s, geometry);
  ASSERT_TRUE(done.ok()) << done.error().message;
  ASSERT_GE(s.fluid.size(), 1u);  // a column of whole layers and at most two boxes of a part layer
  const float d = s.solver.spacing();
  const double samples = sampling::estimate_sample_count(false, 0.0, 1.0, d);
  // ~auto_count samples over the square metre, and one fluid particle per sample.
  EXPECT_NEAR(samples, double(s.sampling.auto_count), 0.25 * double(s.sampling.auto_count));
  sim::ParticleSet fluid;
  ASSERT_TRUE(sim::fill_sources(s.fluid, s.domain, s.solver.particle_radius, fluid).ok());
  EXPECT_EQ(double(fluid.size()), std::round(samples));
  // The fluid starts above the sheet, inside the domain.
  for (const auto& f : s.fluid) {
    EXPECT_GT(f.min.y(), 1.0f);
    EXPECT_TRUE((s.domain.max.array() >= f.max.array()).all());
  }
}

TEST(SheetTarget, AShapeWithNoVolumeAndNoAreaIsStillRefused) {
  scene::Scene s;
  s.targets.emplace_back();
  std::vector<TargetGeometry> geometry(1);
  geometry[0].box.extend(Vec3f::Zero());
  geometry[0].box.extend(Vec3f::Ones());
  const Status done = complete_scene(s, geometry);
  ASSERT_FALSE(done.ok());
  EXPECT_NE(done.error().message.find("no volume and no area"), std::string::npos) << done.error().message;
}

TEST(SheetTarget, ItsMetricsMeasureTheSlabItsSamplesStandFor) {
  const float dc = 0.05f;
  const io::TriangleMesh sheet = square_sheet(1.0f);
  std::vector<Vec3f> samples;
  for (float x = 0.5f * dc; x < 1.0f; x += dc)
    for (float y = 0.5f * dc; y < 1.0f; y += dc) samples.emplace_back(x, y, 0.0f);
  auto shape = metrics::TargetShape::build(sheet, samples, dc);
  ASSERT_TRUE(shape.has_value()) << shape.error().message;
  EXPECT_TRUE(shape->sheet());
  // Both sides alike: −d_c/2 on the sheet, 0 on the slab's faces, + beyond them. On the sheet itself the grid (nodes
  // d_c/2 apart) interpolates the distance's kink linearly: up to d_c/4 more there.
  for (const float z : {0.0f, 0.5f * dc, -0.5f * dc, 1.5f * dc, -1.5f * dc}) {
    const float expect = std::abs(z) - 0.5f * dc;
    EXPECT_NEAR(shape->signed_distance(Vec3f(0.4f, 0.6f, z)), expect, z == 0.0f ? 0.26f * dc : 0.05f * dc) << "z = " << z;
  }
  // Fluid on the sheet's two faces, r = d_c/2 from it, is all inside; a layer 3 r off one side is splash.
  const float r = 0.5f * dc;
  std::vector<Vec3f> fluid;
  for (const Vec3f& p : samples) fluid.push_back(p + Vec3f(0, 0, (fluid.size() % 2 ? r : -r)));
  std::vector<std::uint8_t> ids(fluid.size(), 0), ctrl(fluid.size(), 1);
  auto m = metrics::measure(*shape, 0, fluid, ids, ctrl, r, Eigen::Affine3f::Identity(), 1.0f);
  EXPECT_DOUBLE_EQ(m.inside_fraction, 1.0);
  EXPECT_DOUBLE_EQ(m.splash_fraction, 0.0);
  for (Vec3f& p : fluid) p.z() = 4.0f * r;
  m = metrics::measure(*shape, 0, fluid, ids, ctrl, r, Eigen::Affine3f::Identity(), 1.0f);
  EXPECT_DOUBLE_EQ(m.inside_fraction, 0.0);
  EXPECT_DOUBLE_EQ(m.splash_fraction, 1.0);
}

}  // namespace
}  // namespace ff::pipeline
