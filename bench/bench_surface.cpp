// Surface reconstruction (surface::reconstruct, default parameters: cell d/2, h = 2d, two smoothing passes,
// cluster reduction, decimation to 0.02 d and to 20k triangles) of 100k and 1M particles: a lattice filling a
// sphere, and a jittered, shuffled lattice filling a bunny-like blob (body, head, ears, tail). Counters: final
// and marching-cubes triangles, surface blocks, the field's memory, the peak memory of the call (the process's
// peak RSS reset before it through /proc/self/clear_refs, minus the RSS before it) and per-stage seconds.
//   OMP_NUM_THREADS=2 build/release/bench/bench_surface --benchmark_repetitions=3 --benchmark_report_aggregates_only=true
// With OpenVDB installed (Debian libopenvdb-dev), the same particles also go through OpenVDB's
// ParticlesToLevelSet (spheres of radius d) + one LevelSetFilter Gaussian pass + volumeToMesh at the same voxel
// size d/2: the anchor users know, in the same run (BM_OpenVdb*).
//
// Figures (release build/surface, OMP_NUM_THREADS=2, one iteration each, on the 2-core dev machine while another
// engineer's build ran, load average ~2.5, so these are upper bounds):
//   sphere 100k   0.53 s   136k MC -> 69k reduced -> 20k triangles   field 0.17 s, decimation 0.15 s   +15 MiB
//   sphere 1M     3.3 s    629k MC -> 322k reduced -> 20k            field 1.4 s,  decimation 1.3 s    +59 MiB
//   blob 100k     0.56 s   149k MC -> 84k reduced -> 20k             field 0.27 s, decimation 0.15 s
//   blob 1M       4.8 s    697k MC -> 393k reduced -> 20k            field 2.6 s,  decimation 1.4 s    +56 MiB
// The field keeps 13–15 MiB at 1M particles (4.6k–5.4k surface blocks of 9³ floats).
// Regularised marching tetrahedra (BM_Reconstruct*Rmt: extraction = MarchingTetrahedra; mc_tris counts the
// tetrahedra's triangles), release build/release, OMP_NUM_THREADS=2 nice -n 19, one iteration, load average ~0.8:
//   sphere 100k   0.41 s   391k MT -> 98k regularised -> 20k   tetrahedra 0.045 s, reduction 0.062 s   +35 MiB
//   sphere 1M     2.8 s    1.82M MT -> 459k regularised -> 20k tetrahedra 0.17 s,  reduction 0.27 s    +150 MiB
//   blob 100k     0.42 s   442k MT -> 117k regularised -> 20k
//   blob 1M       3.7 s    2.07M MT -> 543k regularised -> 20k tetrahedra 0.14 s,  reduction 0.33 s    +142 MiB
// The regularised mesh has 0.72–0.78 of marching cubes' triangles (cluster-reduced MC: 0.51–0.56) and the
// tetrahedra ~2.9× them, hence the larger peak memory. Same-machine comparison at 1 thread (`fluidform mesh
// --final-only` on a 100k-particle lattice sphere, reading and writing included): MC 0.39–0.41 s, RMT 0.52–0.53 s.
// peak_MiB counts only pages the call adds to the process (0 when it fits in memory already held).
#include "core/memory.h"
#include "core/timer.h"
#include "surface/reconstruct.h"

#include <benchmark/benchmark.h>
#ifdef FF_HAVE_OPENVDB
#include <openvdb/openvdb.h>
#include <openvdb/tools/LevelSetFilter.h>
#include <openvdb/tools/ParticlesToLevelSet.h>
#include <openvdb/tools/VolumeToMesh.h>
#endif

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

void run(benchmark::State& state, bool blob, surface::Extraction extraction = surface::Extraction::MarchingCubes) {
  float d = 0.0f;
  const auto p = filled(blob ? Inside(in_blob) : Inside(in_sphere), std::size_t(state.range(0)), blob, &d);
  surface::SurfaceParams params;
  params.extraction = extraction;
  surface::SurfaceStats st;
  double peak = 0.0;
  for (auto _ : state) {
    reset_peak_rss();
    const double before = core::current_rss_mib();
    auto mesh = surface::reconstruct(p, d, params, &st);
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
// The same with regularised marching tetrahedra (extraction = MarchingTetrahedra, the default Cluster reduction):
// mc_tris then counts the tetrahedra's triangles, reduced_tris the regularised mesh's.
void BM_ReconstructSphereRmt(benchmark::State& state) { run(state, false, surface::Extraction::MarchingTetrahedra); }
void BM_ReconstructBlobRmt(benchmark::State& state) { run(state, true, surface::Extraction::MarchingTetrahedra); }

#ifdef FF_HAVE_OPENVDB
// OpenVDB's particle list interface (tools/ParticlesToLevelSet.h): positions, one radius for all.
struct VdbParticles {
  using PosType = openvdb::Vec3R;
  const std::vector<Vec3f>* p;
  openvdb::Real radius;
  std::size_t size() const { return p->size(); }
  void getPos(std::size_t n, openvdb::Vec3R& xyz) const { xyz = openvdb::Vec3R((*p)[n].x(), (*p)[n].y(), (*p)[n].z()); }
  void getPosRad(std::size_t n, openvdb::Vec3R& xyz, openvdb::Real& r) const {
    getPos(n, xyz);
    r = radius;
  }
};

void run_openvdb(benchmark::State& state, bool blob) {
  openvdb::initialize();
  float d = 0.0f;
  const auto p = filled(blob ? Inside(in_blob) : Inside(in_sphere), std::size_t(state.range(0)), blob, &d);
  const VdbParticles list{&p, d};
  double t_raster = 0, t_filter = 0, t_mesh = 0, peak = 0;
  std::size_t tris = 0, voxels = 0;
  for (auto _ : state) {
    reset_peak_rss();
    const double before = core::current_rss_mib();
    core::Stopwatch w;
    // Voxel d/2 (our cell), narrow band of 3 voxels each side (OpenVDB's default).
    auto grid = openvdb::createLevelSet<openvdb::FloatGrid>(0.5 * d, 3.0);
    openvdb::tools::ParticlesToLevelSet<openvdb::FloatGrid> raster(*grid);
    raster.rasterizeSpheres(list);
    raster.finalize(true);
    t_raster = w.seconds();
    openvdb::tools::LevelSetFilter<openvdb::FloatGrid> filter(*grid);
    filter.gaussian(1);
    t_filter = w.seconds() - t_raster;
    std::vector<openvdb::Vec3s> points;
    std::vector<openvdb::Vec3I> triangles;
    std::vector<openvdb::Vec4I> quads;
    openvdb::tools::volumeToMesh(*grid, points, triangles, quads, 0.0, 0.0);
    t_mesh = w.seconds() - t_raster - t_filter;
    peak = core::peak_rss_mib() - before;
    tris = triangles.size() + 2 * quads.size();
    voxels = grid->activeVoxelCount();
    benchmark::DoNotOptimize(points.data());
  }
  state.counters["particles"] = double(p.size());
  state.counters["tris"] = double(tris);
  state.counters["active_voxels"] = double(voxels);
  state.counters["peak_MiB"] = peak;
  state.counters["t_raster"] = t_raster;
  state.counters["t_filter"] = t_filter;
  state.counters["t_mesh"] = t_mesh;
}

void BM_OpenVdbSphere(benchmark::State& state) { run_openvdb(state, false); }
void BM_OpenVdbBlob(benchmark::State& state) { run_openvdb(state, true); }
#endif

}  // namespace

BENCHMARK(BM_ReconstructSphere)->Arg(100'000)->Arg(1'000'000)->Unit(benchmark::kMillisecond)->Iterations(1);
BENCHMARK(BM_ReconstructBlob)->Arg(100'000)->Arg(1'000'000)->Unit(benchmark::kMillisecond)->Iterations(1);
BENCHMARK(BM_ReconstructSphereRmt)->Arg(100'000)->Arg(1'000'000)->Unit(benchmark::kMillisecond)->Iterations(1);
BENCHMARK(BM_ReconstructBlobRmt)->Arg(100'000)->Arg(1'000'000)->Unit(benchmark::kMillisecond)->Iterations(1);
#ifdef FF_HAVE_OPENVDB
BENCHMARK(BM_OpenVdbSphere)->Arg(100'000)->Arg(1'000'000)->Unit(benchmark::kMillisecond)->Iterations(1);
BENCHMARK(BM_OpenVdbBlob)->Arg(100'000)->Arg(1'000'000)->Unit(benchmark::kMillisecond)->Iterations(1);
#endif
BENCHMARK_MAIN();
