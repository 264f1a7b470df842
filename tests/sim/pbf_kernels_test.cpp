// The Jacobi passes on cluster pairs (sim/pbf_kernels.h, every Highway target this CPU has) against the solver's
// neighbour-list passes on the same inputs, and their thread-count invariance.
#include "core/simd_target.h"
#include "sim/emitter.h"
#include "sim/pbf_solver.h"

#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <cstdio>

namespace ff::sim {
namespace {

// A block dropped onto the floor: after a few frames it is compressed at the bottom and splashing at the edges.
ParticleSet dropped_block(const SolverParams& sp, const Domain& dom) {
  ParticleSet p;
  EXPECT_TRUE(fill_sources(std::vector<FluidSource>{{FluidSource::Shape::Box, Vec3f(0.1f, 0.1f, 0.05f), Vec3f(0.4f, 0.35f, 0.4f)}},
                           dom, sp.particle_radius, p).ok());
  PbfSolver warm(sp, dom);
  NoController none;
  for (int f = 0; f < 12; ++f) EXPECT_TRUE(warm.advance(p, f / 60.0, 1.0 / 60.0, none).has_value());
  return p;
}

std::vector<Vec3f> by_id(const ParticleSet& p) {
  std::vector<Vec3f> x(p.size());
  for (std::size_t i = 0; i < p.size(); ++i) x[p.id[i]] = p.position[i];
  return x;
}

TEST(PbfKernels, ClusterPassesAgreeWithTheListPassesOnEveryTarget) {
  SolverParams sp;
  sp.particle_radius = 0.008f;  // d = 1.6 cm: ~6k particles
  sp.surface_tension = 0.0f;
  const Domain dom{Vec3f::Zero(), Vec3f(0.5f, 0.5f, 0.8f)};
  const ParticleSet start = dropped_block(sp, dom);
  ASSERT_GT(start.size(), 3000u);
  NoController none;
  // A short sub-step with a fixed sweep count: the pairs within H_p are then the same at x and x*, so the two
  // paths see the same pairs and differ only by float rounding.
  sp.max_iterations = sp.iterations;
  constexpr float kDt = 1e-4f;
  ParticleSet ref = start;
  {
    PbfSolver lists(sp, dom);
    StageTimes t;
    lists.substep(ref, 0.2, kDt, none, t);
  }
  const auto xr = by_id(ref);
  for (const std::string& target : core::simd_targets()) {
    const std::string name = target == "AVX3" ? "avx512" : target == "AVX2" ? "avx2" : target == "SSE4" ? "sse4" : "";
    if (name.empty()) continue;  // the static baseline (SSSE3) is never chosen where SSE4 exists
    ASSERT_TRUE(core::select_simd_target(name).ok());
    ParticleSet q = start;
    PbfSolver clusters(sp, dom);
    clusters.set_cluster_kernels(true);
    StageTimes t;
    clusters.substep(q, 0.2, kDt, none, t);
    const auto xq = by_id(q);
    std::vector<double> diff(xr.size());
    for (std::size_t i = 0; i < xr.size(); ++i) diff[i] = (xq[i] - xr[i]).norm() / sp.spacing();
    std::sort(diff.begin(), diff.end());
    const double median = diff[diff.size() / 2], p99 = diff[diff.size() * 99 / 100], worst = diff.back();
    std::printf("%s: |Δx| / d median %.2e, 99th percentile %.2e, largest %.2e\n", target.c_str(), median, p99, worst);
    // Float tolerance: the lane sums run in another order, AVX2 fuses multiply-adds and 1/|r| comes from rsqrt +
    // a Newton step.
    EXPECT_LT(median, 1e-5) << target;
    EXPECT_LT(p99, 1e-4) << target;
    EXPECT_LT(worst, 1e-3) << target;
  }
  ASSERT_TRUE(core::select_simd_target("auto").ok());
}

TEST(PbfKernels, ClusterPassesAreBitIdenticalForOneAndTwoThreads) {
  SolverParams sp;
  sp.particle_radius = 0.008f;  // d = 1.6 cm: ~6k particles
  const Domain dom{Vec3f::Zero(), Vec3f(0.5f, 0.5f, 0.8f)};
  const ParticleSet start = dropped_block(sp, dom);
  auto run = [&](int threads) {
    omp_set_num_threads(threads);
    ParticleSet q = start;
    PbfSolver s(sp, dom);
    s.set_cluster_kernels(true);
    NoController none;
    for (int f = 0; f < 3; ++f) EXPECT_TRUE(s.advance(q, 0.2 + f / 60.0, 1.0 / 60.0, none).has_value());
    return by_id(q);
  };
  const int t = omp_get_max_threads();
  const auto one = run(1), two = run(2);
  omp_set_num_threads(t);
  EXPECT_EQ(one, two);
}

}  // namespace
}  // namespace ff::sim
