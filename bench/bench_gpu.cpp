// bench_gpu: the GPU sub-step (gpu/pbf_device.h) per pass, from the device's timestamp queries, for a block of fluid of
// 10k and 100k particles (or --particles); beside it, in the same run, the CPU solver's sub-step on the same particles
// with the same work (sim::PbfSolver::substep at the solver's defaults, surface tension and drag included, without a
// controller, with a fixed sweep count; the "force" column holds ρ(x), the forces and the surface tension),
// and what a GPU time follows from: the pairs within h, the candidates the 27 cells offer, and the bytes one sweep
// reads and writes if nothing stays in a cache.
//
//   bench_gpu [--particles 10000,100000] [--repeats 5] [--iterations 4] [--device I] [--no-cpu]
//
// A frame is 2 sub-steps of 1/120 s (the default max_dt at 60 frames/s). Medians of the repeats.
#include "core/timer.h"
#include "gpu/context.h"
#include "gpu/pbf_device.h"
#include "sim/emitter.h"
#include "sim/pbf_solver.h"
#include "sim/surface_tension.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <random>
#include <string>
#include <vector>

namespace {

using namespace ff;

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

std::vector<std::size_t> parse_counts(const std::string& s) {
  std::vector<std::size_t> out;
  std::size_t pos = 0;
  while (pos < s.size()) {
    const std::size_t comma = s.find(',', pos);
    out.push_back(std::strtoull(s.substr(pos, comma - pos).c_str(), nullptr, 10));
    pos = comma == std::string::npos ? s.size() : comma + 1;
  }
  return out;
}

struct Block {
  sim::SolverParams sp;
  sim::Domain dom;
  std::vector<Vec3f> x;
};

// A cube of about n particles at the lattice spacing, jittered by 0.1 d so that λ is not zero everywhere.
Block make_block(std::size_t n) {
  Block b;
  b.sp.particle_radius = 0.01f;
  const float d = b.sp.spacing();
  const float side = std::cbrt(static_cast<float>(n)) * d;
  b.dom.min = Vec3f::Zero();
  b.dom.max = Vec3f::Constant(side + 0.2f);
  sim::ParticleSet p;
  const std::vector<sim::FluidSource> src{{sim::FluidSource::Shape::Box, Vec3f::Constant(0.1f), Vec3f::Constant(0.1f + side)}};
  if (!sim::fill_sources(src, b.dom, b.sp.particle_radius, p).ok()) std::abort();
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> u(-0.1f, 0.1f);
  b.x = p.position;
  for (Vec3f& v : b.x) v += d * Vec3f(u(rng), u(rng), u(rng));
  return b;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::size_t> counts{10000, 100000};
  int repeats = 5, iterations = 4, device = -1;
  bool cpu = true;
  for (int a = 1; a < argc; ++a) {
    const std::string arg = argv[a];
    const auto next = [&]() -> std::string { return a + 1 < argc ? argv[++a] : ""; };
    if (arg == "--particles") counts = parse_counts(next());
    else if (arg == "--repeats") repeats = std::max(1, std::atoi(next().c_str()));
    else if (arg == "--iterations") iterations = std::clamp(std::atoi(next().c_str()), 1, 64);
    else if (arg == "--device") device = std::atoi(next().c_str());
    else if (arg == "--no-cpu") cpu = false;
    else {
      fmt::print(stderr, "usage: bench_gpu [--particles N,N] [--repeats R] [--iterations I] [--device I] [--no-cpu]\n");
      return 2;
    }
  }
  auto ctx = gpu::Context::create({.device = device, .validation = false});
  if (!ctx) {
    fmt::print(stderr, "bench_gpu: {}\n", ctx.error().message);
    return 1;
  }
  const gpu::DeviceInfo& info = (*ctx)->info();
  fmt::print("device: {} ({}), {}, API {}\n", info.name, info.type, info.driver, info.api);
  fmt::print("{} sweeps a sub-step, median of {} sub-steps; GPU ms from timestamp queries; CPU: PbfSolver::substep, "
             "{} threads\n\n",
             iterations, repeats, std::getenv("OMP_NUM_THREADS") ? std::getenv("OMP_NUM_THREADS") : "all");
  fmt::print("{:>9} {:>7} {:>7} {:>7} {:>7} {:>7} {:>7} {:>9} {:>9} {:>9} {:>7} {:>7} {:>9} {:>7}\n", "particles", "grid",
             "force", "λ", "Δx", "copy+err", "update", "sub-step", "frame", "CPU step", "pairs", "cand.", "MB/sweep", "dev MB");
  for (const std::size_t n_want : counts) {
    Block b = make_block(n_want);
    b.sp.vorticity = 0.0f;
    b.sp.iterations = b.sp.max_iterations = iterations;
    const std::size_t n = b.x.size();
    const float dt = 1.0f / 120.0f;
    const sim::PbfSolver solver(b.sp, b.dom);
    const sim::PbfLambdaConsts lk = solver.lambda_consts();
    const sim::PbfDeltaConsts dk = solver.delta_consts();
    sim::PbfForceConsts fk = solver.force_consts(dt);
    fk.st_key = sim::surface_tension_step_key(0.0);  // the CPU sub-step's (time 0)
    auto grid = gpu::GridSpec::for_support(b.dom.min, b.dom.max, lk.h);
    if (!grid) return fmt::print(stderr, "bench_gpu: {}\n", grid.error().message), 1;
    auto dev = gpu::PbfDevice::create(**ctx, n, *grid);
    if (!dev) return fmt::print(stderr, "bench_gpu: {}\n", dev.error().message), 1;
    const std::vector<Vec3f> v0(n, Vec3f::Zero());
    std::vector<std::vector<double>> t(6);
    for (int r = 0; r <= repeats; ++r) {  // the first is a warm-up
      gpu::PassTimes pt;
      if (!(*dev)->set_state(b.x, v0).ok() || !(*dev)->substep(lk, dk, fk, {iterations, iterations, -1.0f}, &pt).ok()) return 1;
      if (r == 0) continue;
      for (int k = 0; const double v : {pt.grid, pt.force, pt.lambda, pt.delta, pt.copy, pt.update}) t[static_cast<std::size_t>(k++)].push_back(v);
    }
    // What the sweeps touch: per particle, the candidates of its 27 cells and the pairs within h (on the CPU, from
    // the device's grid).
    std::vector<std::uint32_t> start, items;
    if (!(*dev)->get_grid(start, items).ok()) return 1;
    const gpu::GridSpec& gs = *grid;
    double candidates = 0, pairs = 0;
    for (std::size_t i = 0; i < n; ++i) {
      int c[3];
      for (int a = 0; a < 3; ++a)
        c[a] = std::clamp(static_cast<int>(std::floor((b.x[i][a] - gs.lo[a]) / gs.cell)), 0, gs.dims[static_cast<std::size_t>(a)] - 1);
      for (int dz = -1; dz <= 1; ++dz)
        for (int dy = -1; dy <= 1; ++dy)
          for (int dxc = -1; dxc <= 1; ++dxc) {
            const int cx = c[0] + dxc, cy = c[1] + dy, cz = c[2] + dz;
            if (cx < 0 || cy < 0 || cz < 0 || cx >= gs.dims[0] || cy >= gs.dims[1] || cz >= gs.dims[2]) continue;
            const std::size_t cell = static_cast<std::size_t>(cx + gs.dims[0] * (cy + gs.dims[1] * cz));
            candidates += start[cell + 1] - start[cell];
            for (std::uint32_t k = start[cell]; k < start[cell + 1]; ++k)
              if (items[k] != i && (b.x[items[k]] - b.x[i]).squaredNorm() < lk.h2) ++pairs;
          }
    }
    // Bytes per sweep with no cache: λ reads per candidate an index and a vec4, per particle its cell, position and
    // 27 cell ranges, and writes density and λ; Δx reads per candidate an index, a vec4 and a λ, and writes a vec4;
    // the copy moves a vec4 each way.
    const double ranges = 27.0 * 8.0 * static_cast<double>(n);
    const double bytes = candidates * 20.0 + static_cast<double>(n) * 28.0 + ranges +   // λ
                         candidates * 24.0 + static_cast<double>(n) * 40.0 + ranges +   // Δx
                         static_cast<double>(n) * 32.0;                                   // copy
    double cpu_ms = 0;
    if (cpu) {
      sim::PbfSolver ref(b.sp, b.dom);
      sim::NoController none;
      std::vector<double> runs;
      for (int r = 0; r <= std::min(repeats, 3); ++r) {
        sim::ParticleSet p;
        p.resize(n);
        for (std::size_t i = 0; i < n; ++i) p.position[i] = b.x[i], p.velocity[i] = Vec3f::Zero(), p.id[i] = static_cast<Index>(i);
        sim::StageTimes st;
        const core::Stopwatch timer;
        ref.substep(p, 0.0, dt, none, st);
        if (r > 0) runs.push_back(timer.seconds() * 1e3);
      }
      cpu_ms = median(runs);
    }
    std::array<double, 6> m{};
    for (std::size_t k = 0; k < 6; ++k) m[k] = median(t[k]);
    const double step = m[0] + m[1] + m[2] + m[3] + m[4] + m[5];
    fmt::print("{:>9} {:>7.2f} {:>7.2f} {:>7.2f} {:>7.2f} {:>7.2f} {:>7.2f} {:>9.2f} {:>9.2f} {:>9} {:>7.1f} {:>7.1f} {:>9.1f} {:>7.1f}\n",
               n, m[0], m[1], m[2] / iterations, m[3] / iterations, m[4] / iterations, m[5], step, 2.0 * step,
               cpu ? fmt::format("{:.2f}", cpu_ms) : "-", pairs / static_cast<double>(n), candidates / static_cast<double>(n),
               bytes / 1e6, static_cast<double>((*dev)->bytes()) / 1e6);
  }
  fmt::print("\nms; λ, Δx and copy are per sweep; pairs and candidates per particle; MB/sweep: λ + Δx + copy with no cache\n");
  return 0;
}
