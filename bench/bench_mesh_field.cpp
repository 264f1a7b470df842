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
//     re-run 2026-12-04, quiet machine, median of 5 (BM_Inside/1000000/{0,1}): the bunny is closed, so inside()
//     counts a ray's crossings: 75.0 ms (13.3 M points/s) against 786 ms by the winding number (1.27 M/s), 10.5×
//   inside, 16 overlapping ellipsoids (7.7k triangles, a character's parts), 200k points (BM_InsideParts):
//                                      13.2 ms by the ray, 175 ms by the winding number: 13.3×
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

#include <cmath>
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

// Inside/outside of every point: by inside() (a ray's crossings on a closed mesh), or by the hierarchical winding
// number > 0.5 (what inside() is on an open one, and was on every mesh before the rays).
void inside_batch(const sampling::MeshField& f, const std::vector<Vec3f>& p, std::vector<std::uint8_t>& out,
                  bool by_ray) {
  if (by_ray) return f.inside(p, out);
  std::vector<float> w(p.size());
  f.winding_number(p, w);
  for (std::size_t i = 0; i < p.size(); ++i) out[i] = w[i] > 0.5f;
}

// state.range(1) = 0: inside(), 1: the winding number.
void BM_Inside(benchmark::State& state) {
  if (!field().closed()) state.SkipWithError("the bunny is not closed");
  const auto p = probes(static_cast<std::size_t>(state.range(0)));
  std::vector<std::uint8_t> out(p.size());
  for (auto _ : state) {
    inside_batch(field(), p, out, state.range(1) == 0);
    benchmark::DoNotOptimize(out.data());
  }
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

// A closed mesh of many overlapping parts, as a skinned character is (the demo character: 16 parts, 6.8k
// triangles): 16 ellipsoids of 480 triangles along a stick figure, 1 m tall. Points as probes() do for the bunny.
const sampling::MeshField& parts_field() {
  static const sampling::MeshField f = [] {
    io::TriangleMesh all;
    for (int k = 0; k < 16; ++k) {
      io::TriangleMesh e = test::uv_sphere(1.0f, 16);
      const float a = 0.39f * float(k);  // the parts turn about the body and climb it, each overlapping the next
      const Vec3f centre(0.18f * std::cos(a), 0.06f * float(k), 0.18f * std::sin(a));
      const Vec3f radii(0.16f, 0.09f, 0.07f);
      for (auto& v : e.vertices) v = centre + v.cwiseProduct(radii);
      all = test::merge(all, e);
    }
    return sampling::MeshField::build(all).value();
  }();
  return f;
}

// inside() on the parts: state.range(1) = 0 by the ray (closed()), 1 by the hierarchical winding number.
void BM_InsideParts(benchmark::State& state) {
  const sampling::MeshField& f = parts_field();
  if (!f.closed()) state.SkipWithError("the parts are not closed");
  const Aabb b = f.bounds();
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::vector<Vec3f> p(static_cast<std::size_t>(state.range(0)));
  for (auto& x : p) x = b.min - 0.1f * b.size() + Vec3f(u(rng), u(rng), u(rng)).cwiseProduct(1.2f * b.size());
  std::vector<std::uint8_t> out(p.size());
  for (auto _ : state) {
    inside_batch(f, p, out, state.range(1) == 0);
    benchmark::DoNotOptimize(out.data());
  }
  state.SetItemsProcessed(state.iterations() * state.range(0));
}

}  // namespace

BENCHMARK(BM_MeshFieldBuild)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Inside)->Args({1'000'000, 0})->Args({1'000'000, 1})->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_InsideParts)->Args({200'000, 0})->Args({200'000, 1})->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_SignedDistance)->Arg(1'000'000)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_SdfGridBuild)->Arg(128)->Arg(256)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_SdfGridSample)->Unit(benchmark::kMillisecond);
BENCHMARK_MAIN();
