// The automatic particle count from the target (pipeline/auto_scene.h, issue 44 item 3): a solid keeps
// sampling.auto_count; a thin-walled target gets the count that puts kWallSpacings spacings across its thinnest
// wall, up to sampling.max_auto_count and what the memory limit allows; a count the scene names is kept.
#include "pipeline/auto_scene.h"
#include "pipeline/run_budget.h"
#include "sampling/samplers.h"
#include "sim/emitter.h"
#include "support/shapes.h"
#include "support/test_support.h"

#include <gtest/gtest.h>

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace ff::pipeline {
namespace {

struct Completed {
  scene::Scene scene;
  std::vector<TargetGeometry> targets;
};

Completed complete(const std::filesystem::path& dir, const std::string& json) {
  auto s = scene::parse_scene(json, dir);
  if (!s) ADD_FAILURE() << s.error().message;
  Completed c{s ? std::move(*s) : scene::Scene{}, {}};
  auto g = load_target_meshes(c.scene);
  if (!g) ADD_FAILURE() << g.error().message;
  if (g) c.targets = std::move(*g);
  const Status st = complete_scene(c.scene, c.targets);
  if (!st.ok()) ADD_FAILURE() << st.error().message;
  return c;
}

class AutoSizing : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = test::temp_dir("auto_sizing");
    test::write_obj(dir_ / "ball.obj", test::uv_sphere(0.5f, 48));
    // A plate 2 cm thick: ~1.6 spacings at 10k particles.
    test::write_obj(dir_ / "plate.obj", test::box(Vec3f(0.5f, 0.01f, 0.5f), 8));
  }
  std::filesystem::path dir_;
};

TEST_F(AutoSizing, AThickShapeKeepsTheCountForItsVolume) {
  const auto c = complete(dir_, R"({"targets": [{"mesh": "ball.obj"}]})");
  EXPECT_EQ(c.scene.sizing.count, 10000.0);
  EXPECT_EQ(c.scene.sizing.count_for_walls, 0.0);  // a ball's walls are its diameter
  const double d = std::cbrt(c.targets[0].field->volume() / 1e4);
  EXPECT_NEAR(c.scene.solver.spacing(), d, 1e-6 * d);
  EXPECT_FALSE(thin_wall_warning(c.scene, 0, c.targets[0]).has_value());
}

TEST_F(AutoSizing, AThinWallGetsThreeSpacingsAcrossIt) {
  const auto c = complete(dir_, R"({"targets": [{"mesh": "plate.obj"}]})");
  const auto& z = c.scene.sizing;
  ASSERT_TRUE(c.targets[0].thickness.has_value());
  const double wall = c.targets[0].thickness->thinnest;
  EXPECT_NEAR(wall, 0.02, 0.002);
  // At 10k the wall would be 1.6 spacings across; (3 / 1.6)³ ≈ 6.7× the count puts three across it.
  const double d10k = std::cbrt(0.02 / 1e4);
  EXPECT_NEAR(z.count_for_walls, 1e4 * std::pow(kWallSpacings * d10k / wall, 3.0), 1.0);
  EXPECT_GT(z.count, 5e4);
  EXPECT_EQ(z.count, z.count_for_walls);
  EXPECT_TRUE(z.limited_by.empty());
  EXPECT_NEAR(wall / c.scene.solver.spacing(), kWallSpacings, 0.01);
  EXPECT_FALSE(thin_wall_warning(c.scene, 0, c.targets[0]).has_value());
  // The fluid is sized at the new spacing: kCellShare (0.955) of the plate's volume.
  EXPECT_NEAR(c.targets[0].volume, 0.955 * 0.02, 0.0003);
}

// A flat target gets nearly as much fluid as its samples stand for (issue 44: the 3 cm gear's fluid was 0.68–0.72 of its
// samples, from a count of the lattice points inside, 4 of its 4.9 layers, and a column that filled only whole layers):
// now kCellShare (0.955) of the cells it covers, to the particle.
TEST_F(AutoSizing, AFlatTargetsFluidNearlyMatchesItsSamples) {
  test::write_obj(dir_ / "gear.obj", test::gear(24, 0.4f, 0.5f, 0.03f));
  // Under a sanitizer the thinner disc only (the 10k sampling is most of this test's ~130 s there).
  for (const double count : {3000.0, 10000.0}) {
    if (test::kSanitized && count > 5000.0) continue;
    const auto c = complete(dir_, fmt::format(R"({{"targets": [{{"mesh": "gear.obj"}}], "sampling": {{"auto_count": {}}}}})", count));
    sim::ParticleSet fluid;
    ASSERT_TRUE(sim::fill_sources(c.scene.fluid, c.scene.domain, c.scene.solver.particle_radius, fluid).ok());
    const float d = c.scene.solver.spacing();
    // The column holds its volume to the particle.
    EXPECT_EQ(double(fluid.size()), std::round(c.targets[0].volume / (double(d) * d * d)));
    EXPECT_GT(double(fluid.size()), 1.05 * double(sampling::voxel_samples(*c.targets[0].field, d).size()));
    sampling::SamplingParams p = c.scene.sampling;
    p.spacing = d;
    auto samples = sampling::sample_target(c.targets[0].mesh, p);
    ASSERT_TRUE(samples.has_value()) << samples.error().message;
    const double ratio = double(fluid.size()) / double(samples->size());
    // At 3000 the disc is 1.7 spacings thick, and the sampler's spacing repair adds ~6 % to what its volume asks for
    // where the relaxation left gaps (3 010 asked, 3 194 made): fluid sized before sampling cannot see those.
    EXPECT_GT(ratio, count < 5000.0 ? 0.86 : 0.92) << count << " samples aimed at: " << fluid.size() << " fluid, "
                                                   << samples->size() << " samples";
    EXPECT_LT(ratio, 0.97) << count;
  }
}

// Columns over targets whose footprints overlap are stacked, not merged (fill_sources counts a shared lattice point
// once): every target's fluid is there to the particle, inside the automatic domain with 2 H_c above it.
TEST_F(AutoSizing, OverlappingColumnsAreStackedAndHoldEveryTargetsFluid) {
  const auto c = complete(dir_, R"({"targets": [{"mesh": "ball.obj"}, {"mesh": "ball.obj", "translate": [0.3, 0.6, 0]}]})");
  ASSERT_EQ(c.targets.size(), 2u);
  sim::ParticleSet fluid;
  ASSERT_TRUE(sim::fill_sources(c.scene.fluid, c.scene.domain, c.scene.solver.particle_radius, fluid).ok());
  const double d3 = std::pow(double(c.scene.solver.spacing()), 3.0);
  const double want = std::round(c.targets[0].volume / d3) + std::round(c.targets[1].volume / d3);
  EXPECT_EQ(double(fluid.size()), want);
  float top = 0.0f;
  for (std::size_t i = 0; i < fluid.size(); ++i) top = std::max(top, fluid.position[i].y());
  EXPECT_LE(top + 2.0f * c.scene.sampling.support_factor * c.scene.solver.spacing(), c.scene.domain.max.y() + 1e-4f);
}

// A container's fluid starts inside it, a spacing over its floor: poured from above its rim, the open box's fluid
// struck the floor at ~4 m/s, ran up the walls, was held there over-full, and the floor kept a hole (bench/RESULTS.md,
// "Detail at scale, ninth part"). A ball's column still starts over its top, and either column holds its count.
TEST_F(AutoSizing, AContainersFluidStartsInsideItOverItsFloor) {
  const float wall = 0.06f;
  test::write_obj(dir_ / "open_box.obj", test::open_box(Vec3f(0.5f, 0.35f, 0.4f), wall));
  for (const char* mesh : {"open_box.obj", "ball.obj"}) {
    const auto c =
        complete(dir_, fmt::format(R"({{"targets": [{{"mesh": "{}"}}], "sampling": {{"auto_count": 3000}}}})", mesh));
    sim::ParticleSet fluid;
    ASSERT_TRUE(sim::fill_sources(c.scene.fluid, c.scene.domain, c.scene.solver.particle_radius, fluid).ok());
    const float d = c.scene.solver.spacing();
    EXPECT_EQ(double(fluid.size()), std::round(c.targets[0].volume / (double(d) * d * d))) << mesh;
    Vec3f lo = Vec3f::Constant(1e9f), hi = Vec3f::Constant(-1e9f);
    for (std::size_t i = 0; i < fluid.size(); ++i)
      lo = lo.cwiseMin(fluid.position[i]), hi = hi.cwiseMax(fluid.position[i]);
    if (std::string(mesh) == "ball.obj") {  // a spacing over its top, on the lattice
      EXPECT_GT(lo.y(), c.targets[0].box.max.y() + 0.5f * d);
      EXPECT_LT(lo.y(), c.targets[0].box.max.y() + 2.5f * d);
      continue;
    }
    // Within the box's cavity: over its floor by about a spacing, under its rim, between its walls.
    const float floor_top = -0.35f + wall;
    EXPECT_GT(lo.y(), floor_top + 0.5f * d);
    EXPECT_LT(lo.y(), floor_top + 2.5f * d);
    EXPECT_LT(hi.y(), 0.35f);
    EXPECT_GT(lo.x(), -0.5f + wall);
    EXPECT_LT(hi.x(), 0.5f - wall);
    EXPECT_GT(lo.z(), -0.4f + wall);
    EXPECT_LT(hi.z(), 0.4f - wall);
  }
  // A second target standing in the box: neither column starts inside it (the box's stands on it, not on the floor).
  test::write_obj(dir_ / "small_ball.obj", test::uv_sphere(0.15f, 24));
  const auto c = complete(dir_, R"({"targets": [{"mesh": "open_box.obj"}, {"mesh": "small_ball.obj",
      "translate": [0, -0.13, 0]}], "sampling": {"auto_count": 3000}})");
  ASSERT_EQ(c.targets.size(), 2u);
  sim::ParticleSet fluid;
  ASSERT_TRUE(sim::fill_sources(c.scene.fluid, c.scene.domain, c.scene.solver.particle_radius, fluid).ok());
  float lowest = 1e9f;
  for (std::size_t i = 0; i < fluid.size(); ++i) lowest = std::min(lowest, fluid.position[i].y());
  EXPECT_GT(lowest, c.targets[1].box.max.y()) << "a column starts inside the ball";
  EXPECT_LT(lowest, 0.35f) << "the fluid starts in the box, not over its rim";
}

TEST_F(AutoSizing, TheBudgetHoldsTheCountBackAndTheLineSaysWhatWouldResolveIt) {
  const auto c = complete(dir_, R"({"targets": [{"mesh": "plate.obj"}], "sampling": {"max_auto_count": 20000}})");
  const auto& z = c.scene.sizing;
  EXPECT_EQ(z.count, 20000.0);
  EXPECT_EQ(z.limited_by, "sampling.max_auto_count");
  EXPECT_NEAR(c.scene.solver.spacing(), std::cbrt(0.02 / 2e4), 0.02 * std::cbrt(0.02 / 2e4));
  const auto line = thin_wall_warning(c.scene, 0, c.targets[0]);
  ASSERT_TRUE(line.has_value());
  EXPECT_NE(line->find("over the budget of 20000 (sampling.max_auto_count)"), std::string::npos) << *line;
  EXPECT_NE(line->find(fmt::format("about {:.3g} particles", z.count_for_walls)), std::string::npos) << *line;
  EXPECT_EQ(line->find('\n'), std::string::npos);
}

TEST_F(AutoSizing, TheMemoryLimitHoldsTheCountBack) {
  // 80 MiB: half of it less the model's 15 MiB base, at 2.6 KiB a particle, leaves room for ~9.8k: the count stays
  // at 10k (it never falls below auto_count), and the run still fits the limit.
  const auto c = complete(dir_, R"({"targets": [{"mesh": "plate.obj"}], "limits": {"max_memory_mb": 80}})");
  EXPECT_EQ(c.scene.sizing.limited_by, "memory");
  EXPECT_EQ(c.scene.sizing.count, 10000.0);
  const auto e = check_run_budget(c.scene, c.targets, std::nullopt);
  EXPECT_TRUE(e.has_value()) << e.error().message;
  // 120 MiB: room for (60 − 15) MiB / 2.6 KiB ≈ 17.7k, and the run's estimate within the limit.
  const auto d = complete(dir_, R"({"targets": [{"mesh": "plate.obj"}], "limits": {"max_memory_mb": 120}})");
  EXPECT_EQ(d.scene.sizing.limited_by, "memory");
  EXPECT_NEAR(d.scene.sizing.count, (0.5 * 120.0 - kBaseMib) * 1024.0 / (kFluidKib + kSampleKib), 1.0);
  const auto f = check_run_budget(d.scene, d.targets, std::nullopt);
  EXPECT_TRUE(f.has_value()) << f.error().message;
  const auto line = thin_wall_warning(d.scene, 0, d.targets[0]);
  ASSERT_TRUE(line.has_value());
  EXPECT_NE(line->find("limits.max_memory_mb"), std::string::npos) << *line;
}

TEST_F(AutoSizing, ACountOrSpacingTheSceneNamesIsKept) {
  const auto counted = complete(dir_, R"({"targets": [{"mesh": "plate.obj"}], "sampling": {"auto_count": 10000}})");
  EXPECT_EQ(counted.scene.sizing.count, 10000.0);
  EXPECT_GT(counted.scene.sizing.count_for_walls, 5e4);  // recorded, not used
  const auto line = thin_wall_warning(counted.scene, 0, counted.targets[0]);
  ASSERT_TRUE(line.has_value());
  EXPECT_NE(line->find("(sampling.auto_count)"), std::string::npos) << *line;
  const auto spaced = complete(dir_, R"({"targets": [{"mesh": "plate.obj"}], "sampling": {"spacing": 0.0126}})");
  EXPECT_EQ(spaced.scene.sizing.count, 10000.0);
  // A scene built in code keeps the count it set.
  EXPECT_FALSE(scene::Scene{}.auto_resolution);
}

TEST_F(AutoSizing, ASkinnedTargetKeepsItsCountAndSaysWhatItsWallsWouldNeed) {
  // The demo character's arms are ~4 cm: 2.3 spacings at 10k. Raised to 3 its walk held worse (bench/RESULTS.md).
  const auto glb = test::source_dir() / "examples" / "generated" / "character.glb";
  ASSERT_TRUE(std::filesystem::exists(glb)) << "run scripts/setup (it writes " << glb << ")";
  const auto c = complete(dir_, R"({"targets": [{"mesh": ")" + glb.string() + R"(", "animation": {"clip": "walk"}}]})");
  EXPECT_EQ(c.scene.sizing.count, 10000.0);
  EXPECT_EQ(c.scene.sizing.limited_by, "skinned");
  EXPECT_GT(c.scene.sizing.count_for_walls, 10000.0);
  const auto line = thin_wall_warning(c.scene, 0, c.targets[0]);
  ASSERT_TRUE(line.has_value());
  EXPECT_NE(line->find("a scene with a skinned target keeps it"), std::string::npos) << *line;
}

}  // namespace
}  // namespace ff::pipeline
