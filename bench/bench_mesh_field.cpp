// Inside/outside and signed distance of a target mesh (sampling/mesh_field, sampling/sdf_grid) on the Stanford
// bunny (npm `bunny`: 1839 vertices, 3674 triangles, scaled to a 1 m bounding-box diagonal): the field's build,
// winding numbers and signed distances for 1M points uniform in the box + 10 %, and the signed distance grid
// at spacing = diagonal / 128 and / 256.
//   build/release/bench/bench_mesh_field --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
//
// Figures (release build/helper, OMP_NUM_THREADS=2, median of 5, on the 2-core dev machine shared with another
// build, load average ~3.5, so these are upper bounds):
//   MeshField::build                   12.6 ms       188 bytes per triangle
//   inside, 1M points                  1.26 s        0.79 M points/s
//   signed_distance, 1M points         1.95 s        0.51 M points/s (closest point + winding number)
//   SdfGrid::build, diagonal / 128     0.34 s        0.48 M nodes (114 k in the exact band, 88 k winding numbers)
//   SdfGrid::build, diagonal / 256     1.33 s        3.44 M nodes: distance 0.77 s, sign 0.55 s (459 k band nodes,
//                                                    356 k winding numbers = 10 %); 4 bytes per node (13.8 MB),
//                                                    16 per node at the build's peak; far nodes: 2.6 % over the
//                                                    exact distance, by ≤ 0.77 spacing
//   SdfGrid::sample, 1M random points  0.14 s        7.0 M samples/s on one thread
#include "sampling/mesh_field.h"
#include "sampling/sdf_grid.h"
#include "support/shapes.h"

#include <benchmark/benchmark.h>

#include <cstdio>
#include <cstdlib>
#include <random>

namespace {
using namespace ff;

io::TriangleMesh bunny() {
  auto r = test::stanford_bunny();
  if (!r) {
    std::fprintf(stderr, "%s\n", r.error().message.c_str());
    std::exit(2);
  }
  io::TriangleMesh m = std::move(r).value();
  const Aabb b = m.bounds();
  const float s = 1.0f / b.size().norm();
  for (auto& v : m.vertices) v = (v - b.min) * s;
  return m;
}

const sampling::MeshField& field() {
  static const sampling::MeshField f = sampling::MeshField::build(bunny()).value();
  return f;
}

std::vector<Vec3f> probes(std::size_t n) {
  const Aabb b = field().bounds();
  const Vec3f lo = b.min - 0.1f * b.size(), size = 1.2f * b.size();
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::vector<Vec3f> p(n);
  for (auto& x : p) x = lo + Vec3f(u(rng), u(rng), u(rng)).cwiseProduct(size);
  return p;
}

void BM_MeshFieldBuild(benchmark::State& state) {
  const io::TriangleMesh m = bunny();
  for (auto _ : state) benchmark::DoNotOptimize(sampling::MeshField::build(m));
  state.counters["bytes/triangle"] = double(field().bytes()) / double(field().triangle_count());
}

void BM_Inside(benchmark::State& state) {
  const auto p = probes(static_cast<std::size_t>(state.range(0)));
  std::vector<std::uint8_t> out(p.size());
  for (auto _ : state) field().inside(p, out);
  state.SetItemsProcessed(state.iterations() * state.range(0));
}

void BM_SignedDistance(benchmark::State& state) {
  const auto p = probes(static_cast<std::size_t>(state.range(0)));
  std::vector<float> out(p.size());
  for (auto _ : state) field().signed_distance(p, out);
  state.SetItemsProcessed(state.iterations() * state.range(0));
}

void BM_SdfGridBuild(benchmark::State& state) {
  const float h = 1.0f / float(state.range(0));  // diagonal is 1 m
  sampling::SdfGridStats stats;
  for (auto _ : state)
    benchmark::DoNotOptimize(sampling::SdfGrid::build(field(), h, 2 * h, core::null_progress(), &stats));
  state.counters["nodes"] = double(stats.nodes);
  state.counters["band"] = double(stats.band_nodes);
  state.counters["winding"] = double(stats.winding_evaluations);
  state.counters["s_dist"] = stats.seconds_distance;
  state.counters["s_sign"] = stats.seconds_sign;
}

void BM_SdfGridSample(benchmark::State& state) {
  const sampling::SdfGrid g = sampling::SdfGrid::build(field(), 1.0f / 256.0f, 2.0f / 256.0f).value();
  const auto p = probes(1'000'000);
  for (auto _ : state) {
    float sum = 0.0f;
    for (const auto& x : p) sum += g.sample(x).distance;
    benchmark::DoNotOptimize(sum);
  }
  state.SetItemsProcessed(state.iterations() * std::int64_t(p.size()));
}

}  // namespace

BENCHMARK(BM_MeshFieldBuild)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Inside)->Arg(1'000'000)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_SignedDistance)->Arg(1'000'000)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_SdfGridBuild)->Arg(128)->Arg(256)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_SdfGridSample)->Unit(benchmark::kMillisecond);
BENCHMARK_MAIN();
