// Cluster sets and cluster-pair lists (core/clusters.h) against brute force, and the Highway target pin.
#include "core/clusters.h"
#include "core/simd_target.h"

#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <random>
#include <set>

namespace ff::core {
namespace {

// A jittered lattice block plus a sparse spray far above it (a stretched column, an outlier cluster box).
std::vector<Vec3f> fluid_like(std::size_t n_side, float d, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> jitter(-0.3f * d, 0.3f * d), spray(0.0f, 1.0f);
  std::vector<Vec3f> p;
  for (std::size_t i = 0; i < n_side; ++i)
    for (std::size_t j = 0; j < n_side; ++j)
      for (std::size_t k = 0; k < n_side; ++k)
        p.emplace_back(float(i) * d + jitter(rng), float(j) * d + jitter(rng), float(k) * d + jitter(rng));
  for (int s = 0; s < 40; ++s) p.emplace_back(spray(rng) * 0.2f, spray(rng) * 0.2f, 0.5f + spray(rng));
  std::shuffle(p.begin(), p.end(), rng);
  return p;
}

TEST(Clusters, EveryPointSitsInExactlyOneLaneAndPaddingIsFar) {
  const float d = 0.02f;
  const auto p = fluid_like(9, d, 1);
  ClusterSet s;
  s.assign(p, d);
  EXPECT_EQ(s.points, p.size());
  std::vector<int> seen(p.size(), 0);
  for (std::size_t k = 0; k < s.padded(); ++k) {
    if (s.point[k] == kInvalidIndex) {
      EXPECT_EQ(s.x[k], kFar);
      continue;
    }
    ++seen[s.point[k]];
    EXPECT_EQ(s.x[k], p[s.point[k]].x());
    const std::size_t c = k / kClusterWidth;
    EXPECT_TRUE((p[s.point[k]].array() >= s.lo[c].array()).all() && (p[s.point[k]].array() <= s.hi[c].array()).all());
  }
  EXPECT_TRUE(std::all_of(seen.begin(), seen.end(), [](int v) { return v == 1; }));
  // Compact clusters: the lattice part fills its lanes (the check fails if clusters were cut across columns).
  EXPECT_GT(double(s.points) / double(s.padded()), 0.6);
}

TEST(Clusters, PairListsCoverEveryPairWithinTheRadius) {
  const float d = 0.02f;
  const auto a = fluid_like(8, d, 2), b = fluid_like(7, d, 3);
  for (const float r : {2.0f * d, 2.8f * d}) {
    ClusterSet ca, cb;
    ca.assign(a, d);
    cb.assign(b, d);
    ClusterPairs pairs;
    ClusterPairScratch scratch;
    build_cluster_pairs(ca, cb, r, pairs, scratch);
    ASSERT_EQ(pairs.size(), ca.clusters);
    // Lane → cluster of each point.
    std::vector<std::size_t> cl_a(a.size()), cl_b(b.size());
    for (std::size_t k = 0; k < ca.padded(); ++k)
      if (ca.point[k] != kInvalidIndex) cl_a[ca.point[k]] = k / kClusterWidth;
    for (std::size_t k = 0; k < cb.padded(); ++k)
      if (cb.point[k] != kInvalidIndex) cl_b[cb.point[k]] = k / kClusterWidth;
    std::size_t missing = 0, within = 0;
    for (std::size_t i = 0; i < a.size(); ++i)
      for (std::size_t j = 0; j < b.size(); ++j) {
        if ((a[i] - b[j]).squaredNorm() > r * r) continue;
        ++within;
        const auto l = pairs.of(cl_a[i]);
        missing += !std::binary_search(l.begin(), l.end(), static_cast<Index>(cl_b[j]));
      }
    EXPECT_GT(within, 1000u);
    EXPECT_EQ(missing, 0u) << "r = " << r;
    for (std::size_t c = 0; c < pairs.size(); ++c) {
      const auto l = pairs.of(c);
      EXPECT_TRUE(std::is_sorted(l.begin(), l.end()));
      EXPECT_EQ(std::adjacent_find(l.begin(), l.end()), l.end());
    }
  }
}

TEST(Clusters, ListsDoNotDependOnTheThreadCount) {
  const float d = 0.02f;
  const auto p = fluid_like(10, d, 4);
  auto build = [&](int threads) {
    omp_set_num_threads(threads);
    ClusterSet s;
    s.assign(p, d);
    ClusterPairs pairs;
    ClusterPairScratch scratch;
    build_cluster_pairs(s, s, 2.0f * d, pairs, scratch);
    return std::make_pair(std::vector<Index>(s.point.begin(), s.point.end()), pairs.j);
  };
  const int t = omp_get_max_threads();
  const auto one = build(1), two = build(2);
  omp_set_num_threads(t);
  EXPECT_EQ(one, two);
}

TEST(SimdTarget, PinsEachTargetTheCpuHasAndNamesBadOnes) {
  const auto all = simd_targets();
  ASSERT_FALSE(all.empty());
  for (const std::string name : {"sse4", "avx2", "avx512"}) {
    const std::string upper = name == "avx512" ? "AVX3" : name == "avx2" ? "AVX2" : "SSE4";
    const bool has = std::find(all.begin(), all.end(), upper) != all.end();
    const Status s = select_simd_target(name);
    EXPECT_EQ(s.ok(), has) << name;
    if (has) {
      EXPECT_EQ(simd_target(), upper);
    } else {
      EXPECT_NE(s.error().message.find(name), std::string::npos);
    }
  }
  const Status bad = select_simd_target("neon9");
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.error().message.find("unknown instruction set"), std::string::npos);
  ASSERT_TRUE(select_simd_target("auto").ok());
  EXPECT_EQ(simd_target(), all.front());
}

}  // namespace
}  // namespace ff::core
