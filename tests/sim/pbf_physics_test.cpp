// Physics acceptance (slow, release build only): a resting column stays at rest, a dam break
// conserves particles and stays finite for 10 s of simulated time.
#include "sim/emitter.h"
#include "sim/pbf_solver.h"

#include <gtest/gtest.h>

#include <cmath>

namespace ff::sim {
namespace {

double kinetic_energy(const ParticleSet& p, float m) {
  double e = 0.0;
  for (const auto& v : p.velocity) e += 0.5 * m * v.squaredNorm();
  return e;
}

TEST(PbfPhysics, RestingColumnStaysAtRest) {
  // 27 × 27 × 27 = 19,683 particles of d = 5 cm filling the bottom of a tank exactly.
  SolverParams sp;  // defaults: 4 iterations, Δt ≤ 1/120 s, g = (0, −10, 0)
  const float side = 27 * sp.spacing();
  const Domain dom{Vec3f::Zero(), Vec3f(side, 2.0f * side, side)};
  ParticleSet p;
  ASSERT_TRUE(fill_sources(std::vector<FluidSource>{{FluidSource::Shape::Box, Vec3f::Zero(), Vec3f::Constant(side)}},
                           dom, sp.particle_radius, p).ok());
  ASSERT_EQ(p.size(), 19683u);
  PbfSolver solver(sp, dom);
  NoController none;
  double e_early = 0.0, e_late = 0.0, peak_e = 0.0;
  FrameStats last;
  const int frames = 180;  // 3 s
  for (int f = 0; f < frames; ++f) {
    auto st = solver.advance(p, f / 60.0, 1.0 / 60.0, none);
    ASSERT_TRUE(st.has_value()) << st.error().message;
    last = *st;
    const double e = kinetic_energy(p, solver.particle_mass());
    peak_e = std::max(peak_e, e);
    if (f >= 20 && f < 40) e_early += e;
    if (f >= frames - 20) e_late += e;
  }
  EXPECT_LT(last.density_error_mean, 0.01) << "mean density error";
  EXPECT_LT(last.density_error_max, 0.05) << "max density error";
  EXPECT_LT(e_late, e_early) << "kinetic energy must decay (early " << e_early << ", late " << e_late << ")";
  // "At rest": the late kinetic energy is a small fraction of the potential energy of one spacing of drop.
  const double m = solver.particle_mass(), n = double(p.size());
  EXPECT_LT(e_late / 20.0, 0.01 * n * m * 10.0 * sp.spacing()) << "the column keeps moving";
  for (const auto& x : p.position) {
    ASSERT_TRUE(x.allFinite());
    ASSERT_TRUE((x.array() >= dom.min.array()).all() && (x.array() <= dom.max.array()).all());
  }
  // The column keeps its height: settling is a small fraction of the height.
  float top = 0.0f;
  for (const auto& x : p.position) top = std::max(top, x.y());
  EXPECT_GT(top, side - 0.1f * side);
  std::printf("resting column: mean density error %.4f %%, max %.3f %%, E_kin late/early %.3g\n",
              100 * last.density_error_mean, 100 * last.density_error_max, e_late / e_early);
}

TEST(PbfPhysics, DamBreakConservesParticlesAndStaysFiniteFor10s) {
  SolverParams sp;
  sp.particle_radius = 0.015f;  // ~4.4k particles: 10 s in seconds of wall time
  const Domain dom{Vec3f::Zero(), Vec3f(1.6f, 1.0f, 0.4f)};
  ParticleSet p;
  ASSERT_TRUE(fill_sources(std::vector<FluidSource>{{FluidSource::Shape::Box, Vec3f::Zero(), Vec3f(0.48f, 0.63f, 0.39f)}},
                           dom, sp.particle_radius, p).ok());
  const std::size_t n = p.size();
  PbfSolver solver(sp, dom);
  NoController none;
  double max_speed = 0.0, mean_err = 0.0;
  int frames = 600;
  for (int f = 0; f < frames; ++f) {
    auto st = solver.advance(p, f / 60.0, 1.0 / 60.0, none);
    ASSERT_TRUE(st.has_value()) << "frame " << f << ": " << st.error().message;
    max_speed = std::max(max_speed, st->max_speed);
    if (f >= frames - 60) mean_err += st->density_error_mean / 60.0;
  }
  ASSERT_EQ(p.size(), n);
  for (const auto& x : p.position) ASSERT_TRUE(x.allFinite());
  // The front must have run along the tank: a dam break, not a frozen block.
  float front = 0.0f;
  for (const auto& x : p.position) front = std::max(front, x.x());
  EXPECT_GT(front, 1.4f);
  EXPECT_LT(max_speed, 10.0) << "free-fall from 0.64 m gives ~3.6 m/s; far more means an instability";
  EXPECT_LT(mean_err, 0.01) << "settled dam break should be near rest density";
  std::printf("dam break: %zu particles, max speed %.2f m/s, settled mean density error %.3f %%\n", n, max_speed,
              100 * mean_err);
}

}  // namespace
}  // namespace ff::sim
