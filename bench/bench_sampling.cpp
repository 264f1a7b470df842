// Blue-noise volume sampling of the Stanford bunny (npm package `bunny`, scaled to 1 m tall) at 10k,
// 100k and 1M samples: the whole of sample_target (SDF grid, candidates, sample elimination,
// 100 relaxation steps, spacing repair, weights). Reports seconds per run and the process's peak memory
// (VmHWM only grows: the sizes run in ascending order, so each row's peak is its own).
//   build/release/bench/bench_sampling --benchmark_repetitions=3 --benchmark_report_aggregates_only=true
#include "core/memory.h"
#include "sampling/samplers.h"
#include "support/shapes.h"

#include <benchmark/benchmark.h>

#include <cmath>

namespace {
using namespace ff;

const io::TriangleMesh& bunny() {
  static const io::TriangleMesh mesh = [] {
    auto m = test::stanford_bunny();
    if (!m) throw std::runtime_error(m.error().message);
    io::TriangleMesh b = std::move(*m);
    const Aabb box = b.bounds();
    const float s = 1.0f / box.size().y();
    for (auto& v : b.vertices) v = (v - box.min) * s;
    return b;
  }();
  return mesh;
}

void BM_BlueNoiseBunny(benchmark::State& state) {
  (void)bunny();  // load outside the timing
  sampling::SamplingParams p;
  p.auto_count = static_cast<std::size_t>(state.range(0));
  sampling::SampleReport rep;
  std::size_t n = 0;
  for (auto _ : state) {
    auto set = sampling::sample_target(bunny(), p, 0, &rep);
    if (!set) {
      state.SkipWithError(set.error().message.c_str());
      return;
    }
    n = set->size();
  }
  state.counters["samples"] = double(n);
  state.counters["spacing_mm"] = 1e3 * rep.spacing;
  state.counters["peak_rss_mib"] = core::peak_rss_mib();
  state.counters["s_field"] = rep.t_field;
  state.counters["s_sdf"] = rep.t_sdf;
  state.counters["s_init"] = rep.t_init;
  state.counters["s_relax"] = rep.t_relax;
  state.counters["s_repair"] = rep.t_repair;
  state.counters["s_weights"] = rep.t_weights;
}
BENCHMARK(BM_BlueNoiseBunny)->Arg(10'000)->Arg(100'000)->Arg(1'000'000)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);

}  // namespace

BENCHMARK_MAIN();
