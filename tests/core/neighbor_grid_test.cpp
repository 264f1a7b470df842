// Neighbour search against a brute-force oracle (CompactNSearch demo idea) on random, clustered and
// sparse (hashed-key) point sets, plus the permutation helpers.
#include "core/neighbor_grid.h"

#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <random>

namespace ff::core {
namespace {

std::vector<Vec3f> random_points(std::size_t n, float extent, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, extent);
  std::vector<Vec3f> p(n);
  for (auto& x : p) x = Vec3f(u(rng), u(rng), u(rng));
  return p;
}

std::vector<Vec3f> clustered_points(std::size_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<float> g(0.0f, 0.05f);
  std::uniform_real_distribution<float> u(-5.0f, 5.0f);
  std::vector<Vec3f> centres(6);
  for (auto& c : centres) c = Vec3f(u(rng), u(rng), u(rng));
  std::vector<Vec3f> p(n);
  for (std::size_t i = 0; i < n; ++i) p[i] = centres[i % centres.size()] + Vec3f(g(rng), g(rng), g(rng));
  // A few exact duplicates and a far outlier: both must be handled.
  p[1] = p[0];
  p[n - 1] = Vec3f(1000.0f, -1000.0f, 3.0f);
  return p;
}

std::vector<std::vector<Index>> brute_force(const std::vector<Vec3f>& a, const std::vector<Vec3f>& q, float r,
                                            bool self) {
  std::vector<std::vector<Index>> out(q.size());
  for (std::size_t i = 0; i < q.size(); ++i)
    for (std::size_t j = 0; j < a.size(); ++j)
      if (!(self && i == j) && (a[j] - q[i]).squaredNorm() < r * r) out[i].push_back(static_cast<Index>(j));
  return out;
}

void expect_equal(const NeighborList& got, const std::vector<std::vector<Index>>& want) {
  ASSERT_EQ(got.size(), want.size());
  std::size_t total = 0;
  for (std::size_t i = 0; i < want.size(); ++i) {
    auto g = std::vector<Index>(got.of(i).begin(), got.of(i).end());
    std::sort(g.begin(), g.end());
    ASSERT_EQ(g, want[i]) << "point " << i;
    total += g.size();
  }
  EXPECT_EQ(got.total(), total);
}

TEST(NeighborGrid, EqualsBruteForceOnRandomPoints) {
  const auto p = random_points(3000, 1.0f, 1);
  NeighborGrid grid(0.08f);
  grid.build(p);
  EXPECT_FALSE(grid.hashed());
  NeighborList nl;
  grid.neighbors(p, nl);
  expect_equal(nl, brute_force(p, p, 0.08f, true));
}

TEST(NeighborGrid, EqualsBruteForceOnClusteredPointsWithHashedCells) {
  const auto p = clustered_points(4000, 2);
  NeighborGrid grid(0.03f);
  grid.build(p);
  EXPECT_TRUE(grid.hashed()) << "a 2000 m box at 3 cm cells must use hashed keys";
  NeighborList nl;
  grid.neighbors(p, nl);
  expect_equal(nl, brute_force(p, p, 0.03f, true));
}

TEST(NeighborGrid, QueryOtherSetEqualsBruteForce) {
  const auto p = random_points(2000, 1.0f, 3);
  auto q = random_points(500, 1.4f, 4);  // some queries lie outside the binned box
  for (auto& x : q) x -= Vec3f::Constant(0.2f);
  NeighborGrid grid(0.1f);
  grid.build(p);
  NeighborList nl;
  grid.query(p, q, 0.07f, nl);
  expect_equal(nl, brute_force(p, q, 0.07f, false));
}

// any_within is query() asked only "is there one?": both grids (dense and hashed keys), queries outside the box.
TEST(NeighborGrid, AnyWithinAgreesWithTheFullQuery) {
  for (const bool hashed : {false, true}) {
    const auto p = hashed ? clustered_points(4000, 7) : random_points(2000, 1.0f, 8);
    // Queries around the same clusters (a copy of the points, jittered) or over a box larger than the points'.
    auto q = hashed ? clustered_points(3000, 7) : random_points(3000, 1.4f, 10);
    std::mt19937 rng(12);
    std::normal_distribution<float> jitter(0.0f, 0.03f);
    for (auto& x : q) x += hashed ? Vec3f(jitter(rng), jitter(rng), jitter(rng)) : Vec3f::Constant(-0.2f);
    const float r = hashed ? 0.03f : 0.07f;
    NeighborGrid grid(hashed ? 0.03f : 0.1f);
    grid.build(p);
    ASSERT_EQ(grid.hashed(), hashed);
    std::vector<std::uint8_t> hit;
    grid.any_within(p, q, r, hit);
    ASSERT_EQ(hit.size(), q.size());
    const auto want = brute_force(p, q, r, false);
    std::size_t hits = 0;
    for (std::size_t i = 0; i < q.size(); ++i) {
      EXPECT_EQ(hit[i] != 0, !want[i].empty()) << "query " << i << (hashed ? " (hashed)" : " (dense)");
      hits += hit[i];
    }
    EXPECT_GT(hits, q.size() / 20) << "the sets must be close enough for hits";
    EXPECT_LT(hits, q.size()) << "and sparse enough for misses";
  }
}

// The dense-key limit is the caller's: a grid that would hash by default stays dense with a higher limit, and its
// lists are exact either way.
TEST(NeighborGrid, AHigherDenseLimitKeepsKeysDenseAndListsExact) {
  const auto p = random_points(3000, 1.0f, 11);
  const float r = 0.04f;  // with the margins 29³ = 24 389 cells for 3 000 points: past 2 per point, within 8
  NeighborGrid hashed(r), dense(r, 8.0);
  hashed.build(p);
  dense.build(p);
  EXPECT_TRUE(hashed.hashed());
  EXPECT_FALSE(dense.hashed());
  NeighborList a, b;
  hashed.neighbors(p, a);
  dense.neighbors(p, b);
  expect_equal(a, brute_force(p, p, r, true));
  expect_equal(b, brute_force(p, p, r, true));
}

TEST(NeighborGrid, SortedOrderThenNeighborsStillExact) {
  auto p = random_points(2500, 0.7f, 5);
  NeighborGrid grid(0.06f);
  grid.build(p);
  std::vector<Vec3f> scratch;
  apply_permutation(p, std::span<const Index>(grid.sorted()), scratch);
  grid.points_were_sorted();
  NeighborList nl;
  grid.neighbors(p, nl);
  EXPECT_TRUE(nl.compact) << "points in cell order must get 16-bit lists";
  expect_equal(nl, brute_force(p, p, 0.06f, true));
}

TEST(NeighborGrid, CompactAndWideListsAgreeInOrder) {
  auto p = random_points(4000, 0.8f, 9);
  NeighborGrid grid(0.07f);
  grid.build(p);
  std::vector<Vec3f> scratch;
  apply_permutation(p, std::span<const Index>(grid.sorted()), scratch);
  grid.build(p);  // same order again, but not declared sorted: wide lists
  NeighborList wide;
  grid.neighbors(p, wide);
  EXPECT_FALSE(wide.compact);
  grid.points_were_sorted();
  NeighborList compact;
  grid.neighbors(p, compact);
  ASSERT_TRUE(compact.compact);
  EXPECT_LT(compact.bytes(), wide.bytes());
  for (std::size_t i = 0; i < p.size(); ++i) {
    const auto a = wide.of(i), b = compact.of(i);
    ASSERT_TRUE(std::equal(a.begin(), a.end(), b.begin(), b.end())) << "point " << i;
  }
}

TEST(NeighborGrid, DenseClumpFallsBackToWideListsAndStaysExact) {
  // 2000 points inside one cell: a row holds more than 12-bit offsets can address.
  auto p = random_points(2000, 0.01f, 10);
  const auto spread = random_points(500, 1.0f, 11);
  p.insert(p.end(), spread.begin(), spread.end());
  NeighborGrid grid(0.05f);
  grid.build(p);
  std::vector<Vec3f> scratch;
  apply_permutation(p, std::span<const Index>(grid.sorted()), scratch);
  grid.points_were_sorted();
  EXPECT_GE(grid.max_cell_points(), 2000u);
  NeighborList nl;
  grid.neighbors(p, nl);
  EXPECT_FALSE(nl.compact);
  expect_equal(nl, brute_force(p, p, 0.05f, true));
}

TEST(NeighborGrid, ListsIndependentOfThreadCount) {
  const auto p = clustered_points(5000, 6);
  NeighborGrid grid(0.04f);
  const int saved = omp_get_max_threads();
  omp_set_num_threads(1);
  grid.build(p);
  const auto sorted1 = grid.sorted();
  NeighborList a;
  grid.neighbors(p, a);
  omp_set_num_threads(std::max(2, saved));
  grid.build(p);
  NeighborList b;
  grid.neighbors(p, b);
  omp_set_num_threads(saved);
  EXPECT_EQ(sorted1, grid.sorted());
  for (std::size_t i = 0; i < p.size(); ++i) {
    const auto x = a.of(i), y = b.of(i);
    ASSERT_TRUE(std::equal(x.begin(), x.end(), y.begin(), y.end())) << "point " << i;
  }
}

TEST(Permutation, ReorderThenInverseIsIdentity) {
  std::vector<Index> perm(1000);
  for (Index i = 0; i < perm.size(); ++i) perm[i] = i;
  std::shuffle(perm.begin(), perm.end(), std::mt19937(7));
  const auto original = random_points(1000, 1.0f, 8);
  auto a = original;
  std::vector<Vec3f> scratch;
  apply_permutation(a, std::span<const Index>(perm), scratch);
  EXPECT_EQ(a[0], original[perm[0]]);
  const auto inv = inverse_permutation(perm);
  apply_permutation(a, std::span<const Index>(inv), scratch);
  EXPECT_EQ(a, original);
}

}  // namespace
}  // namespace ff::core
