// Surface reconstruction (surface::reconstruct, default parameters: cell d/2, h = 2d, two smoothing passes,
// cluster reduction, decimation to 0.02 d and to 20k triangles) of 100k and 1M particles: a lattice filling a
// sphere, and a jittered, shuffled lattice filling a bunny-like blob (body, head, ears, tail). Counters: final
// and marching-cubes triangles, surface blocks, the field's memory, the peak memory of the call (the process's
// peak RSS reset before it through /proc/self/clear_refs, minus the RSS before it) and per-stage seconds.
//   OMP_NUM_THREADS=2 build/release/bench/bench_surface
//
// Figures (release build/surface, OMP_NUM_THREADS=2, one iteration each, on the 2-core dev machine while another
// engineer's build ran, load average ~2.5, so these are upper bounds):
//   sphere 100k   0.53 s   136k MC -> 69k reduced -> 20k triangles   field 0.17 s, decimation 0.15 s   +15 MiB
//   sphere 1M     3.3 s    629k MC -> 322k reduced -> 20k            field 1.4 s,  decimation 1.3 s    +59 MiB
//   blob 100k     0.56 s   149k MC -> 84k reduced -> 20k             field 0.27 s, decimation 0.15 s
//   blob 1M       4.8 s    697k MC -> 393k reduced -> 20k            field 2.6 s,  decimation 1.4 s    +56 MiB
// The field keeps 13–15 MiB at 1M particles (4.6k–5.4k surface blocks of 9³ floats).
// peak_MiB counts only pages the call adds to the process (0 when it fits in memory already held).
#include "core/memory.h"
#include "surface/reconstruct.h"

#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <random>

namespace {
using namespace ff;

using Inside = std::function<bool(const Vec3f&)>;

bool in_ellipsoid(const Vec3f& p, const Vec3f& c, const Vec3f& r) {
  return ((p - c).array() / r.array()).matrix().squaredNorm() < 1.0f;
}

bool in_blob(const Vec3f& p) {
  return in_ellipsoid(p, {0, 0, 0}, {1.0f, 0.8f, 0.75f}) || in_ellipsoid(p, {0.9f, 0.7f, 0}, Vec3f::Constant(0.5f)) ||
         in_ellipsoid(p, {0.8f, 1.45f, 0.2f}, {0.12f, 0.45f, 0.08f}) ||
         in_ellipsoid(p, {0.8f, 1.45f, -0.2f}, {0.12f, 0.45f, 0.08f}) ||
         in_ellipsoid(p, {-1.0f, -0.1f, 0}, Vec3f::Constant(0.25f));
}

bool in_sphere(const Vec3f& p) { return p.squaredNorm() < 1.0f; }

std::vector<Vec3f> lattice(const Inside& inside, float d, bool jitter) {
  std::vector<Vec3f> p;
  const int n = int(std::ceil(2.0f / d));
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> u(-0.15f * d, 0.15f * d);
  for (int k = -n; k <= n; ++k)
    for (int j = -n; j <= n; ++j)
      for (int i = -n; i <= n; ++i) {
        const Vec3f x(float(i) * d, float(j) * d, float(k) * d);
        if (inside(x)) p.push_back(jitter ? Vec3f(x + Vec3f(u(rng), u(rng), u(rng))) : x);
      }
  if (jitter) std::shuffle(p.begin(), p.end(), rng);  // no help from lattice order: simulated particles are mixed
  return p;
}

// Particles filling the shape at a spacing chosen so that about n fit.
std::vector<Vec3f> filled(const Inside& inside, std::size_t n, bool jitter, float* spacing) {
  float d = 0.05f;
  for (int it = 0; it < 3; ++it) d *= float(std::cbrt(double(lattice(inside, d, false).size()) / double(n)));
  *spacing = d;
  return lattice(inside, d, jitter);
}

void reset_peak_rss() {
  if (std::FILE* f = std::fopen("/proc/self/clear_refs", "w")) {
    std::fputs("5", f);  // resets VmHWM to the current RSS (Linux ≥ 4.0)
    std::fclose(f);
  }
}

void run(benchmark::State& state, bool blob) {
  float d = 0.0f;
  const auto p = filled(blob ? Inside(in_blob) : Inside(in_sphere), std::size_t(state.range(0)), blob, &d);
  surface::SurfaceStats st;
  double peak = 0.0;
  for (auto _ : state) {
    reset_peak_rss();
    const double before = core::current_rss_mib();
    auto mesh = surface::reconstruct(p, d, surface::SurfaceParams{}, &st);
    peak = core::peak_rss_mib() - before;
    if (!mesh) state.SkipWithError(mesh.error().message.c_str());
    benchmark::DoNotOptimize(mesh);
  }
  state.counters["particles"] = double(p.size());
  state.counters["tris"] = double(st.check.triangles);
  state.counters["mc_tris"] = double(st.mc_triangles);
  state.counters["reduced_tris"] = double(st.reduced_triangles);
  state.counters["blocks"] = double(st.surface_blocks);
  state.counters["field_MiB"] = double(st.field_bytes) / (1024.0 * 1024.0);
  state.counters["peak_MiB"] = peak;
  state.counters["t_field"] = st.t_field;
  state.counters["t_mc"] = st.t_mc;
  state.counters["t_smooth"] = st.t_smooth;
  state.counters["t_reduce"] = st.t_reduce;
  state.counters["t_decimate"] = st.t_decimate;
  state.counters["t_check"] = st.t_check;
  state.counters["ok"] = st.check.ok() ? 1.0 : 0.0;
}

void BM_ReconstructSphere(benchmark::State& state) { run(state, false); }
void BM_ReconstructBlob(benchmark::State& state) { run(state, true); }

}  // namespace

BENCHMARK(BM_ReconstructSphere)->Arg(100'000)->Arg(1'000'000)->Unit(benchmark::kMillisecond)->Iterations(1);
BENCHMARK(BM_ReconstructBlob)->Arg(100'000)->Arg(1'000'000)->Unit(benchmark::kMillisecond)->Iterations(1);
BENCHMARK_MAIN();
