// One PBF sub-step (4 iterations, neighbour search and re-sort included) on a dam break at 10k, 100k
// and 1M particles. Reports particle-steps per second and bytes of solver state per particle.
//   build/release/bench/bench_pbf_step --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
// The second argument picks the Jacobi passes: 0 = neighbour lists (the solver's default), 1 = cluster pairs
// (Highway kernels, sim/pbf_kernels.h) on the instruction set in the context line (FF_SIMD=sse4|avx2|avx512 pins one).
#include "core/simd_target.h"
#include "sim/emitter.h"
#include "sim/pbf_solver.h"

#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdio>

namespace {
using namespace ff;

// A dam-break block of ~n particles (d = 5 cm), in a tank 3× as long, already collapsing.
struct DamBreak {
  sim::SolverParams params;
  sim::Domain domain;
  sim::ParticleSet particles;
  explicit DamBreak(std::size_t n) {
    params.max_iterations = params.iterations;  // exactly 4 sweeps, as in the SPlisHSPlasH anchor
    const float d = params.spacing();
    const int side = static_cast<int>(std::cbrt(double(n) / 2.0));  // block side × 2·side × side
    const float s = static_cast<float>(side) * d;
    const Vec3f block(s, 2.0f * s, s);
    domain = {Vec3f::Zero(), Vec3f(3.0f * block.x(), 1.2f * block.y(), block.z())};
    sim::FluidSource src{sim::FluidSource::Shape::Box, Vec3f::Zero(), block};
    (void)sim::fill_sources(std::vector<sim::FluidSource>{src}, domain, params.particle_radius, particles);
  }
};

void BM_PbfStep(benchmark::State& state) {
  DamBreak scene(static_cast<std::size_t>(state.range(0)));
  sim::PbfSolver solver(scene.params, scene.domain);
  solver.set_cluster_kernels(state.range(1) == 1);
  sim::NoController none;
  sim::StageTimes times;
  const float dt = 1.0f / 120.0f;
  double t = 0.0;
  for (int i = 0; i < 6; ++i, t += dt) solver.substep(scene.particles, t, dt, none, times);  // start collapsing
  // Every timed step starts from the same 16-step window of the collapse: a benchmark that simply ran on
  // would time a different flow (eventually a clumped one) depending on how many iterations it chose.
  const sim::ParticleSet start = scene.particles;
  const double t0 = t;
  times = {};
  int k = 0;
  for (auto _ : state) {
    if (++k % 16 == 0) {
      state.PauseTiming();
      scene.particles = start;
      t = t0;
      state.ResumeTiming();
    }
    solver.substep(scene.particles, t, dt, none, times);
    t += dt;
  }
  // Where a step's time goes (ms per step, mean over the timed steps).
  const double per = 1e3 / double(state.iterations());
  state.counters["search_ms"] = times.neighbors * per;
  state.counters["forces_ms"] = times.forces * per;
  state.counters["solve_ms"] = times.solve * per;
  state.counters["update_ms"] = times.update * per;
  const double n = double(scene.particles.size());
  state.SetItemsProcessed(static_cast<std::int64_t>(double(state.iterations()) * n));
  state.counters["particles"] = n;
  state.counters["bytes_per_particle"] = double(scene.particles.bytes() + solver.scratch_bytes()) / n;
  state.counters["neighbors_per_particle"] = double(solver.neighbors().total()) / n;
}
BENCHMARK(BM_PbfStep)
    ->ArgsProduct({{10'000, 100'000, 1'000'000}, {0, 1}})
    ->ArgNames({"n", "clusters"})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace

int main(int argc, char** argv) {
  if (const ff::Status s = ff::core::select_simd_target_from_env(); !s.ok()) {
    std::fprintf(stderr, "%s\n", s.error().message.c_str());
    return 2;
  }
  benchmark::AddCustomContext("simd_target", ff::core::simd_target());
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
