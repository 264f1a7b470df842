// The run's memory estimate (pipeline/run_budget.h): what it counts, and that the check refuses with the figures.
#include "pipeline/run_budget.h"
#include "sampling/sdf_grid.h"

#include <gtest/gtest.h>

namespace ff::pipeline {
namespace {

scene::Scene scene_with_spacing(float d) {
  scene::Scene s;
  s.solver.particle_radius = 0.5f * d;
  s.fluid.clear();
  return s;
}

TargetGeometry target(const Vec3f& lo, const Vec3f& hi, double volume, double area) {
  TargetGeometry t;
  t.box.extend(lo);
  t.box.extend(hi);
  t.volume = volume;
  t.area = area;
  return t;
}

TEST(RunBudget, CountsTheTargetsSdfGridsBesideTheirSamples) {
  const float d = 0.01f;
  const scene::Scene scene = scene_with_spacing(d);
  // A solid cube filling its box: the grids are small next to its samples.
  const auto solid = estimate_run(scene, {target(Vec3f::Zero(), Vec3f::Constant(0.3f), 0.027, 0.54)});
  EXPECT_NEAR(double(solid.control_samples), 0.027 / (d * d * d), 0.05 * 0.027 / (d * d * d));
  EXPECT_LT(solid.sdf_mib, 0.25 * (solid.memory_mib - kBaseMib));
  // A thin wire frame across a metre box (0.1 litre): few samples, a grid over the whole box. Its grids are most of
  // what the run holds.
  const auto sheet = estimate_run(scene, {target(Vec3f::Zero(), Vec3f::Constant(1.0f), 1e-4, 0.5)});
  Aabb box;
  box.extend(Vec3f::Zero());
  box.extend(Vec3f::Constant(1.0f));
  const double metric_nodes = sampling::sdf_node_count(box, sampling::auto_sdf_spacing(box, 3.0f * d, d), 3.0f * d);
  EXPECT_GT(sheet.sdf_mib, 4.0 * metric_nodes / (1024.0 * 1024.0));
  EXPECT_GT(sheet.sdf_mib, 0.9 * (sheet.memory_mib - kBaseMib));
  // Two targets: the metrics' grids add up, the sampling peak is the larger one's.
  const auto two = estimate_run(scene, {target(Vec3f::Zero(), Vec3f::Constant(1.0f), 1e-4, 0.5),
                                        target(Vec3f::Zero(), Vec3f::Constant(1.0f), 1e-4, 0.5)});
  EXPECT_GT(two.sdf_mib, sheet.sdf_mib);
  EXPECT_LT(two.sdf_mib, 2.0 * sheet.sdf_mib);
}

TEST(RunBudget, AGridCappedAtItsNodeLimitIsCountedAtTheCap) {
  // A kilometre box: the automatic spacing coarsens until the grid has at most kAutoSdfNodes nodes.
  Aabb huge;
  huge.extend(Vec3f::Zero());
  huge.extend(Vec3f::Constant(1000.0f));
  const float s = sampling::auto_sdf_spacing(huge, 0.02f, 0.01f);
  EXPECT_LE(sampling::sdf_node_count(huge, s, 0.02f), sampling::kAutoSdfNodes);
  EXPECT_GT(sampling::sdf_node_count(huge, s / 1.25f, 0.02f), sampling::kAutoSdfNodes);
  const auto e = estimate_run(scene_with_spacing(0.01f), {target(Vec3f::Zero(), Vec3f::Constant(1000.0f), 0.0, 6e6)});
  EXPECT_LE(e.sdf_mib, 20.0 * sampling::kAutoSdfNodes / (1024.0 * 1024.0));
}

TEST(RunBudget, OverTheLimitIsAParamErrorNamingEstimateLimitAndKnobs) {
  const scene::Scene scene = scene_with_spacing(0.01f);
  const std::vector<TargetGeometry> sheet{target(Vec3f::Zero(), Vec3f::Constant(1.0f), 1e-4, 0.5)};
  const auto e = estimate_run(scene, sheet);
  auto ok = check_run_budget(scene, sheet, 2.0 * e.memory_mib);
  ASSERT_TRUE(ok.has_value());
  EXPECT_EQ(ok->limit_mib, 2.0 * e.memory_mib);
  auto refused = check_run_budget(scene, sheet, 0.5 * e.memory_mib);
  ASSERT_FALSE(refused.has_value());
  EXPECT_EQ(refused.error().kind, Error::Kind::Param);
  const std::string& m = refused.error().message;
  for (const char* part : {"MiB of SDF grids", "more than the limit", "limits.max_memory_mb", "--max-memory"})
    EXPECT_NE(m.find(part), std::string::npos) << part << " in " << m;
}

}  // namespace
}  // namespace ff::pipeline
