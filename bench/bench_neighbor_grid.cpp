// Neighbour search alone (binning + CSR lists) on fluid-like point sets (a jittered lattice of spacing d,
// radius 2d as in the solver) at 250k and 1M points.
//   build/release/bench/bench_neighbor_grid --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
#include "core/neighbor_grid.h"

#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <random>

namespace {
using namespace ff;

std::vector<Vec3f> jittered_lattice(std::size_t n, float d) {
  const int side = static_cast<int>(std::cbrt(double(n)));
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> u(-0.15f * d, 0.15f * d);
  std::vector<Vec3f> p;
  p.reserve(std::size_t(side) * side * side);
  for (int k = 0; k < side; ++k)
    for (int j = 0; j < side; ++j)
      for (int i = 0; i < side; ++i) p.emplace_back(float(i) * d + u(rng), float(j) * d + u(rng), float(k) * d + u(rng));
  // Shuffle so the benchmark does not profit from lattice order (a sorted solver state would).
  std::shuffle(p.begin(), p.end(), rng);
  return p;
}

void BM_NeighborSearch(benchmark::State& state) {
  const float d = 0.05f;
  auto p = jittered_lattice(static_cast<std::size_t>(state.range(0)), d);
  const bool sorted = state.range(1) != 0;
  core::NeighborGrid grid(2.0f * d);
  core::NeighborList nl;
  if (sorted) {  // the solver's case: particles are kept in cell order between steps
    grid.build(p);
    std::vector<Vec3f> scratch;
    core::apply_permutation(p, std::span<const Index>(grid.sorted()), scratch);
  }
  for (auto _ : state) {
    grid.build(p);
    if (sorted) grid.points_were_sorted();  // as the solver does after re-ordering its arrays
    grid.neighbors(p, nl);
    benchmark::DoNotOptimize(nl.index.data());
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(p.size()));
  state.counters["neighbors_per_point"] = double(nl.total()) / double(p.size());
  state.counters["compact"] = nl.compact ? 1.0 : 0.0;
  state.counters["bytes_per_point"] = double(nl.bytes() + grid.bytes()) / double(p.size());
}
BENCHMARK(BM_NeighborSearch)
    ->ArgNames({"n", "cell_sorted"})
    ->Args({250'000, 1})
    ->Args({1'000'000, 1})
    ->Args({250'000, 0})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
