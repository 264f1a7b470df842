// The nearest-seed field under the gather term (control/nearest_seed_field.h): against brute force, the seed it
// names for a point is never farther than the true nearest seed by more than the cell's diagonal.
#include "control/nearest_seed_field.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace ff::control {
namespace {

struct Cloud {
  std::vector<Vec3f> points;
  std::vector<Index> seeds;
};

Cloud random_cloud(std::size_t n, std::size_t seeds, float extent, unsigned rng_seed) {
  std::mt19937 rng(rng_seed);
  std::uniform_real_distribution<float> u(0.0f, extent);
  Cloud c;
  for (std::size_t i = 0; i < n; ++i) c.points.emplace_back(u(rng), u(rng), u(rng));
  for (std::size_t k = 0; k < seeds; ++k) c.seeds.push_back(static_cast<Index>(rng() % n));
  return c;
}

float true_nearest(const Cloud& c, const Vec3f& p) {
  float best = INFINITY;
  for (Index s : c.seeds) best = std::min(best, (c.points[s] - p).norm());
  return best;
}

// Largest miss over `probes` random points, in units of `cell`.
float worst_excess(const NearestSeedField& f, const Cloud& c, float extent, float cell, int probes) {
  std::mt19937 rng(99);
  std::uniform_real_distribution<float> u(0.0f, extent);
  float worst = 0.0f;
  for (int q = 0; q < probes; ++q) {
    const Vec3f p(u(rng), u(rng), u(rng));
    const Index s = f.nearest(p);
    EXPECT_NE(s, kInvalidIndex);
    if (s == kInvalidIndex) return INFINITY;
    EXPECT_NE(std::find(c.seeds.begin(), c.seeds.end(), s), c.seeds.end()) << "not a seed: " << s;
    worst = std::max(worst, ((c.points[s] - p).norm() - true_nearest(c, p)) / cell);
  }
  return worst;
}

TEST(NearestSeedField, NamesASeedWithinACellDiagonalOfTheNearest) {
  const float extent = 2.0f, cell = 0.1f;
  for (const std::size_t seeds : {1u, 5u, 60u, 600u}) {
    const Cloud c = random_cloud(3000, seeds, extent, 7 + static_cast<unsigned>(seeds));
    NearestSeedField f;
    f.reset(Vec3f::Zero(), Vec3f::Constant(extent), cell);
    f.compute(c.points, c.seeds);
    ASSERT_FALSE(f.empty());
    const float excess = worst_excess(f, c, extent, cell, 2000);
    EXPECT_LE(excess, std::sqrt(3.0f)) << seeds << " seeds";
  }
}

TEST(NearestSeedField, AHugeDomainIsCoarsenedToTheCellBudgetAndStillAnswers) {
  const float extent = 50.0f;
  const std::size_t max_cells = 4096;  // 16³: the requested 0.01 m cells would be 5000³
  const Cloud c = random_cloud(2000, 40, extent, 3);
  NearestSeedField f;
  f.reset(Vec3f::Zero(), Vec3f::Constant(extent), 0.01f, max_cells);
  f.compute(c.points, c.seeds);
  // The coarsened cell is at most 1.25× the smallest edge that fits the budget.
  const float cell = 1.25f * extent / (std::floor(std::cbrt(float(max_cells))) - 1.0f);
  EXPECT_LE(worst_excess(f, c, extent, cell, 1000), std::sqrt(3.0f));
}

TEST(NearestSeedField, NoSeedsMeansNoAnswerAndRecomputingForgetsOldSeeds) {
  const Cloud c = random_cloud(100, 10, 1.0f, 5);
  NearestSeedField f;
  f.reset(Vec3f::Zero(), Vec3f::Ones(), 0.1f);
  EXPECT_TRUE(f.empty());
  EXPECT_EQ(f.nearest(Vec3f::Constant(0.5f)), kInvalidIndex);
  f.compute(c.points, c.seeds);
  EXPECT_NE(f.nearest(Vec3f::Constant(0.5f)), kInvalidIndex);
  // One seed left: every point of the domain (and outside it, clamped) names it.
  const std::vector<Index> one{c.seeds[3]};
  f.compute(c.points, one);
  for (const Vec3f& p : {Vec3f(0, 0, 0), Vec3f(1, 1, 1), Vec3f(0.3f, 0.9f, 0.1f), Vec3f(-5, 7, 0.5f)})
    EXPECT_EQ(f.nearest(p), one[0]);
  f.compute(c.points, {});
  EXPECT_TRUE(f.empty());
  EXPECT_EQ(f.nearest(Vec3f::Constant(0.5f)), kInvalidIndex);
}

TEST(NearestSeedField, TheSameSeedsGiveTheSameField) {
  const Cloud c = random_cloud(2000, 50, 1.0f, 11);
  NearestSeedField a, b;
  a.reset(Vec3f::Zero(), Vec3f::Ones(), 0.05f);
  b.reset(Vec3f::Zero(), Vec3f::Ones(), 0.05f);
  a.compute(c.points, c.seeds);
  b.compute(c.points, c.seeds);
  for (const Vec3f& p : c.points) EXPECT_EQ(a.nearest(p), b.nearest(p));
}

}  // namespace
}  // namespace ff::control
