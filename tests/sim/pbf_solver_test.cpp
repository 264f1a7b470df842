// Fast solver checks: calibration, a resting lattice without gravity stays put, sources, walls, blow-up.
#include "sim/pbf_solver.h"

#include "sim/emitter.h"
#include "sim/pbf_constraints.h"

#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>
#include <limits>

namespace ff::sim {
namespace {

TEST(PbfSolver, RestDensityIsCalibratedToTheLattice) {
  SolverParams sp;
  PbfSolver solver(sp, Domain{});
  // METHOD.md §c.1: the Poly6 lattice sum at h = 2d is 1.010 / d³.
  EXPECT_NEAR(solver.rest_density() / sp.rest_density, 1.010, 0.002);
  EXPECT_FLOAT_EQ(solver.particle_mass(), sp.rest_density * std::pow(sp.spacing(), 3.0f));
  EXPECT_GT(solver.s0(), 0.0f);
}

TEST(PbfSolver, InteriorOfARestingLatticeHasZeroConstraint) {
  SolverParams sp;
  sp.gravity = Vec3f::Zero();
  const Domain dom{Vec3f::Zero(), Vec3f::Constant(1.0f)};
  ParticleSet p;
  ASSERT_TRUE(fill_sources(std::vector<FluidSource>{{FluidSource::Shape::Box, Vec3f::Zero(), Vec3f::Constant(1.0f)}},
                           dom, sp.particle_radius, p).ok());
  EXPECT_EQ(p.size(), 20u * 20u * 20u);
  PbfSolver solver(sp, dom);
  solver.compute_densities(p);
  double max_err = 0.0;
  for (std::size_t i = 0; i < p.size(); ++i) max_err = std::max<double>(max_err, density_constraint(p.density[i], solver.rest_density()));
  EXPECT_LT(max_err, 1e-5) << "a resting lattice must start exactly at rest density";
}

TEST(PbfSolver, NoGravityLatticeStaysAtRest) {
  SolverParams sp;
  sp.gravity = Vec3f::Zero();
  // The walls have no boundary particles, so a box-filling lattice has a "free surface" at every wall and
  // surface tension would round its corners: this test is about PBF's rest state only.
  sp.surface_tension = 0.0f;
  const Domain dom{Vec3f::Zero(), Vec3f::Constant(0.6f)};
  ParticleSet p;
  ASSERT_TRUE(fill_sources(std::vector<FluidSource>{{FluidSource::Shape::Box, Vec3f::Zero(), Vec3f::Constant(0.6f)}},
                           dom, sp.particle_radius, p).ok());
  const auto start = p.position;
  const auto ids = p.id;
  PbfSolver solver(sp, dom);
  NoController none;
  for (int f = 0; f < 10; ++f) ASSERT_TRUE(solver.advance(p, f / 60.0, 1.0 / 60.0, none).has_value());
  double max_move = 0.0;
  for (std::size_t i = 0; i < p.size(); ++i) max_move = std::max<double>(max_move, (p.position[i] - start[p.id[i]]).norm());
  // Only s_corr acts on a full lattice at the walls: the particles may settle by a tiny fraction of d.
  EXPECT_LT(max_move, 0.05 * sp.spacing());
}

TEST(PbfSolver, WallsKeepParticlesInsideAndCountIsConserved) {
  SolverParams sp;
  sp.particle_radius = 0.02f;
  const Domain dom{Vec3f::Zero(), Vec3f(0.8f, 0.8f, 0.4f)};
  ParticleSet p;
  FluidSource s{FluidSource::Shape::Sphere};
  s.center = Vec3f(0.4f, 0.5f, 0.2f);
  s.radius = 0.15f;
  s.velocity = Vec3f(5.0f, -3.0f, 1.0f);  // thrown hard against the walls
  ASSERT_TRUE(fill_sources(std::vector<FluidSource>{s}, dom, sp.particle_radius, p).ok());
  const std::size_t n = p.size();
  EXPECT_NEAR(double(n), 4.0 / 3.0 * M_PI * std::pow(0.15 / 0.04, 3), 0.1 * double(n));
  PbfSolver solver(sp, dom);
  NoController none;
  for (int f = 0; f < 30; ++f) {
    auto st = solver.advance(p, f / 60.0, 1.0 / 60.0, none);
    ASSERT_TRUE(st.has_value());
    EXPECT_GE(st->substeps, 2) << "5 m/s at d = 4 cm needs CFL sub-steps";
  }
  ASSERT_EQ(p.size(), n);
  for (std::size_t i = 0; i < n; ++i) {
    ASSERT_TRUE((p.position[i].array() >= dom.min.array() + sp.particle_radius - 1e-6f).all());
    ASSERT_TRUE((p.position[i].array() <= dom.max.array() - sp.particle_radius + 1e-6f).all());
  }
}

TEST(PbfSolver, CapillarySubStepShrinksAsTheSpacingToTheThreeHalves) {
  SolverParams sp;
  sp.particle_radius = 0.025f;  // d = 0.05 m, the reference spacing: σ_eff = 0.05 / 0.05² = 20 N/m, H_p = 0.1 m
  const double h = 0.1, sigma = 20.0;
  EXPECT_NEAR(sp.capillary_dt(), 0.4 * std::sqrt(1000.0 * h * h * h / (2.0 * M_PI * sigma)), 1e-7);
  SolverParams fine = sp;
  fine.particle_radius = 0.025f / 4.0f;
  EXPECT_NEAR(fine.capillary_dt() / sp.capillary_dt(), 1.0 / 8.0, 1e-6);  // (1/4)^1.5
  SolverParams off = fine;
  off.capillary_cfl = 0.0f;
  EXPECT_TRUE(std::isinf(off.capillary_dt()));
  off = fine;
  off.surface_tension = 0.0f;
  EXPECT_TRUE(std::isinf(off.capillary_dt()));
}

TEST(PbfSolver, AFrameTakesTheSubStepsTheCapillaryConditionNeeds) {
  // A resting drop at d = 5 mm: the CFL rule alone allows 1/120 s (2 sub-steps of a 1/60 s frame); the capillary
  // condition allows ~1.13 ms (H_p = 1 cm), so 15 sub-steps; with it off, 2.
  SolverParams sp;
  sp.particle_radius = 0.0025f;
  sp.gravity = Vec3f::Zero();
  const Domain dom{Vec3f::Zero(), Vec3f(0.1f, 0.1f, 0.1f)};
  FluidSource s{FluidSource::Shape::Sphere};
  s.center = Vec3f(0.05f, 0.05f, 0.05f);
  s.radius = 0.02f;
  const int expected = static_cast<int>(std::ceil((1.0 / 60.0) / sp.capillary_dt() - 1e-9));
  EXPECT_EQ(expected, 15);
  for (const float c : {0.4f, 0.0f}) {
    sp.capillary_cfl = c;
    ParticleSet p;
    ASSERT_TRUE(fill_sources(std::vector<FluidSource>{s}, dom, sp.particle_radius, p).ok());
    PbfSolver solver(sp, dom);
    NoController none;
    const auto st = solver.advance(p, 0.0, 1.0 / 60.0, none);
    ASSERT_TRUE(st.has_value());
    EXPECT_EQ(st->substeps, c > 0.0f ? expected : 2) << "capillary_cfl " << c;
  }
}

TEST(PbfSolver, NonFiniteStateIsReportedWithTheParticleId) {
  SolverParams sp;
  const Domain dom{Vec3f::Zero(), Vec3f::Constant(0.5f)};
  ParticleSet p;
  ASSERT_TRUE(fill_sources(std::vector<FluidSource>{{FluidSource::Shape::Box, Vec3f::Zero(), Vec3f::Constant(0.3f)}},
                           dom, sp.particle_radius, p).ok());
  p.velocity[17] = Vec3f(std::numeric_limits<float>::quiet_NaN(), 0.0f, 0.0f);
  PbfSolver solver(sp, dom);
  NoController none;
  auto st = solver.advance(p, 0.0, 1.0 / 60.0, none);
  ASSERT_FALSE(st.has_value());
  EXPECT_EQ(st.error().kind, Error::Kind::Numerical);
  EXPECT_NE(st.error().message.find("particle 17"), std::string::npos) << st.error().message;
}

TEST(Emitter, RefusesTooManyParticlesWithAnEstimate) {
  const Domain dom{Vec3f::Zero(), Vec3f::Constant(10.0f)};
  ParticleSet p;
  auto st = fill_sources(std::vector<FluidSource>{{FluidSource::Shape::Box, Vec3f::Zero(), Vec3f::Constant(10.0f)}},
                         dom, 0.001f, p, 1'000'000);
  ASSERT_FALSE(st.ok());
  EXPECT_NE(st.error().message.find("about"), std::string::npos) << st.error().message;
  EXPECT_EQ(p.size(), 0u);
}

TEST(Emitter, OverlappingSourcesShareLatticePointsAndOutsideSourceIsAnError) {
  const Domain dom{Vec3f::Zero(), Vec3f::Constant(1.0f)};
  ParticleSet p;
  FluidSource a{FluidSource::Shape::Box, Vec3f::Zero(), Vec3f::Constant(0.5f)};
  FluidSource b{FluidSource::Shape::Box, Vec3f::Constant(0.25f), Vec3f::Constant(0.75f)};
  ASSERT_TRUE(fill_sources(std::vector<FluidSource>{a, b}, dom, 0.025f, p).ok());
  EXPECT_EQ(p.size(), 1000u + 1000u - 125u) << "10³ + 10³ minus the 5³ shared points";
  ParticleSet q;
  FluidSource out{FluidSource::Shape::Box, Vec3f::Constant(2.0f), Vec3f::Constant(3.0f)};
  auto st = fill_sources(std::vector<FluidSource>{out}, dom, 0.025f, q);
  ASSERT_FALSE(st.ok());
  EXPECT_NE(st.error().message.find("fluid[0]"), std::string::npos);
}

// A column cut to an exact count: whole layers of its footprint from the bottom, then a part layer row by row.
TEST(Emitter, BoxesForACountFillExactlyThatCountFromTheBottomOfTheColumn) {
  const Domain dom{Vec3f::Zero(), Vec3f::Constant(1.0f)};
  const float r = 0.025f;  // lattice at 0.025 + 0.05 i: a 0.2 × 0.2 footprint holds 4 × 4 points
  const FluidSource column{FluidSource::Shape::Box, Vec3f(0.3f, 0.1f, 0.3f), Vec3f(0.5f, 0.2f, 0.5f)};
  for (const std::size_t count : {0u, 1u, 3u, 4u, 7u, 16u, 17u, 37u, 100u}) {
    const auto boxes = boxes_for_count(column, dom, r, count);
    EXPECT_LE(boxes.size(), 3u);
    ParticleSet p;
    if (count > 0) {
      ASSERT_TRUE(fill_sources(boxes, dom, r, p).ok()) << count;
    }
    EXPECT_EQ(p.size(), count);
    float top = 0.0f;
    for (std::size_t i = 0; i < p.size(); ++i) {
      EXPECT_GE(p.position[i].x(), 0.3f);
      EXPECT_LE(p.position[i].x(), 0.5f);
      EXPECT_GE(p.position[i].y(), 0.1f);
      top = std::max(top, p.position[i].y());
    }
    // The lowest layer that holds them all: ⌈count / 16⌉ layers from y = 0.125.
    if (count > 0) {
      EXPECT_NEAR(top, 0.125f + 0.05f * float((count + 15) / 16 - 1), 1e-5f) << count;
    }
  }
  // A footprint off the domain's lattice holds nothing.
  EXPECT_TRUE(boxes_for_count({FluidSource::Shape::Box, Vec3f::Constant(2.0f), Vec3f::Constant(3.0f)}, dom, r, 5).empty());
}

}  // namespace
}  // namespace ff::sim
