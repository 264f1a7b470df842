// Surface tension (Zorilla et al., METHOD.md §a.4 eq. 13, §c.6) and drag (Gissler et al., eq. 14, §c.7) on small
// particle sets with known geometry, and the solver with both forces on.
#include "sim/drag.h"
#include "sim/emitter.h"
#include "sim/pbf_solver.h"
#include "sim/surface_tension.h"

#include "core/neighbor_grid.h"

#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <numeric>

namespace ff::sim {
namespace {

constexpr float kD = 0.05f, kH = 2.0f * kD;  // spacing and support of the defaults (r = 0.025 m)
constexpr float kMass = 1000.0f * kD * kD * kD;
constexpr float kDt = 1.0f / 120.0f;

// Particles with their neighbour lists (radius h, self excluded), as the solver builds them.
struct Cloud {
  std::vector<Vec3f> x;
  std::vector<Index> id;
  core::NeighborGrid grid{kH};
  core::NeighborList nb;
  explicit Cloud(std::vector<Vec3f> pts, std::vector<Index> ids = {}) : x(std::move(pts)), id(std::move(ids)) {
    if (id.empty()) {
      id.resize(x.size());
      std::iota(id.begin(), id.end(), Index{0});
    }
    grid.build(x);
    grid.neighbors(x, nb);
  }
};

std::vector<Vec3f> block(int n) {
  std::vector<Vec3f> x;
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) x.emplace_back(float(i) * kD, float(j) * kD, float(k) * kD);
  return x;
}

// A ball of radius R built from concentric spherical shells d apart, each a spherical Fibonacci set with one point
// per d² (a smooth surface, unlike the terraces of a lattice ball), centred at the origin. Only the polar cap within
// `cap` metres of the north pole (0, R, 0) is kept, plus h of margin so that kept surface points have complete
// neighbourhoods. The outer shell comes first: its first `*outer` points.
std::vector<Vec3f> shell_ball(float radius, float cap, std::size_t* outer) {
  std::vector<Vec3f> x;
  const double golden = M_PI * (3.0 - std::sqrt(5.0)), keep = double(cap) + double(kH);
  for (int s = 0;; ++s) {
    const double rho = double(radius) - s * double(kD);
    if (rho < 0.5 * double(kD)) {
      x.emplace_back(0.0f, 0.0f, 0.0f);
      break;
    }
    if (double(radius) - rho > keep + double(kH)) break;  // deeper than any kept neighbourhood reaches
    const auto n = std::lround(4.0 * M_PI * rho * rho / (double(kD) * double(kD)));
    const double z_min = 1.0 - keep * keep / (2.0 * double(radius) * rho);  // chord `keep` from the pole
    for (long k = 0; k < n; ++k) {
      const double z = 1.0 - (2.0 * double(k) + 1.0) / double(n);
      if (z < z_min) break;
      const double r = std::sqrt(std::max(0.0, 1.0 - z * z)), phi = golden * double(k) + 0.7 * s;  // shells twisted
      x.emplace_back(float(rho * r * std::cos(phi)), float(rho * z), float(rho * r * std::sin(phi)));
    }
    if (s == 0) *outer = x.size();
  }
  return x;
}

SurfaceTensionParams st_params() {
  SurfaceTensionParams p;
  p.support = kH;
  p.mass = kMass;
  return p;
}

bool is_surface(const SurfaceTension& st, std::size_t i) { return st.classes()[i] == std::uint8_t(SurfaceClass::Surface); }

struct BallReading {
  double curvature = 0, normal_dot = 1, accel_dot = -1;  // means over the probed surface particles; worst dots
  int probed = 0, surface = 0;
};

// Mean smoothed κ over the outer-shell particles within `probe` of the pole of a shell ball of radius R.
BallReading read_ball(float radius, float probe, std::uint64_t key) {
  std::size_t outer = 0;
  Cloud cl(shell_ball(radius, probe + kH, &outer));
  std::vector<Vec3f> a(cl.x.size(), Vec3f::Zero());
  SurfaceTension st;
  st.add_accelerations(cl.x, cl.id, cl.nb, st_params(), kDt, key, a);
  BallReading r;
  const Vec3f pole(0.0f, radius, 0.0f);
  for (std::size_t i = 0; i < outer; ++i) {
    if ((cl.x[i] - pole).norm() > probe) continue;
    ++r.probed;
    if (!is_surface(st, i)) continue;
    ++r.surface;
    const Vec3f out = cl.x[i].normalized();
    r.curvature += st.curvatures()[i];
    r.normal_dot = std::min(r.normal_dot, double(st.normals()[i].dot(out)));
    r.accel_dot = std::max(r.accel_dot, double(a[i].normalized().dot(out)));
  }
  r.curvature /= std::max(r.surface, 1);
  return r;
}

TEST(SurfaceTension, ClassifiesTheOuterLayerOfALatticeBlockAndNotItsInterior) {
  constexpr int n = 10;
  Cloud cl(block(n));
  std::vector<Vec3f> a(cl.x.size(), Vec3f::Zero());
  SurfaceTension st;
  st.add_accelerations(cl.x, cl.id, cl.nb, st_params(), kDt, 1, a);
  int outer = 0, inner = 0, faces = 0, edges = 0;
  double face_curvature = 0.0, edge_curvature = 0.0;
  for (std::size_t i = 0; i < cl.x.size(); ++i) {
    const Vec3f q = cl.x[i] / kD;
    const int boundary_axes = int(((q.array() < 0.5f) || (q.array() > float(n) - 1.5f)).count());
    if (boundary_axes > 0) {
      ++outer;
      EXPECT_TRUE(is_surface(st, i)) << "outer-layer particle at " << q.transpose() << " class " << int(st.classes()[i]);
      if (boundary_axes == 1) {
        ++faces;
        face_curvature += st.raw_curvatures()[i];
      } else {
        ++edges;
        edge_curvature += st.raw_curvatures()[i];
      }
    } else {
      ++inner;
      EXPECT_EQ(st.classes()[i], std::uint8_t(SurfaceClass::Interior)) << "interior particle at " << q.transpose();
      EXPECT_EQ(a[i], Vec3f::Zero());
    }
  }
  EXPECT_EQ(outer, n * n * n - (n - 2) * (n - 2) * (n - 2));
  // Faces read nearly flat, edges and corners clearly convex.
  face_curvature /= faces;
  edge_curvature /= edges;
  EXPECT_GT(face_curvature, -0.05 / kH);
  EXPECT_LT(face_curvature, 0.25 / kH);
  EXPECT_GT(edge_curvature, face_curvature + 1.0 / kH);
  EXPECT_EQ(inner, (n - 2) * (n - 2) * (n - 2));
}

// The Monte-Carlo formula reads the mean curvature 1/R of a ball (not the sum 2/R of both principal curvatures: for
// a particle on the surface of a ball the free cap of its r1-sphere gives κ = 1/R + O(h/R²) in the continuum), on
// top of a constant reading of a flat surface (≈ 0.12/h: the gaps between particles uncover a little more than the
// continuum's 10 %). Averages over ~50–200 surface particles, N = 83 stratified points each, are good to a few %.
TEST(SurfaceTension, CurvatureOfABallIsOneOverItsRadiusAboveTheFlatReading) {
  const BallReading flat = read_ball(1000.0f * kD, 4.0f * kH, 11);
  ASSERT_GT(flat.surface, 150);
  EXPECT_EQ(flat.surface, flat.probed) << "every outer-shell particle is a surface particle";
  EXPECT_GT(flat.curvature, 0.0) << "flat reading";
  EXPECT_LT(flat.curvature, 0.25 / kH) << "flat reading";
  for (float radius : {4.0f * kD, 8.0f * kD}) {
    const BallReading ball = read_ball(radius, std::min(radius, 4.0f * kH), 12);
    ASSERT_GT(ball.surface, 40);
    EXPECT_EQ(ball.surface, ball.probed);
    const double excess = (ball.curvature - flat.curvature) * radius;  // (κ − κ_flat) R ≈ 1
    std::printf("R = %.2f m: mean κ %.3f /m, flat %.3f /m, (κ − flat)·R = %.3f\n", double(radius), ball.curvature,
                flat.curvature, excess);
    EXPECT_GT(excess, 0.85) << "R = " << radius << ": κ " << ball.curvature << ", flat " << flat.curvature;
    EXPECT_LT(excess, 1.15) << "R = " << radius << ": κ " << ball.curvature << ", flat " << flat.curvature;
  }
}

TEST(SurfaceTension, NormalsPointOutOfTheFluidAndTheAccelerationInward) {
  std::size_t outer = 0;
  const float radius = 6.0f * kD;
  Cloud cl(shell_ball(radius, 2.0f * radius, &outer));  // the whole ball
  std::vector<Vec3f> a(cl.x.size(), Vec3f::Zero());
  SurfaceTension st;
  st.add_accelerations(cl.x, cl.id, cl.nb, st_params(), kDt, 5, a);
  int surface = 0;
  for (std::size_t i = 0; i < outer; ++i) {
    ASSERT_TRUE(is_surface(st, i)) << i;
    ++surface;
    const Vec3f out = cl.x[i].normalized();
    EXPECT_GT(st.raw_normals()[i].dot(out), 0.95f) << "Monte-Carlo normal of particle " << i;
    EXPECT_GT(st.normals()[i].dot(out), 0.97f) << "smoothed normal of particle " << i;
    EXPECT_NEAR(st.normals()[i].norm(), 1.0f, 1e-5f);
    EXPECT_LT(a[i].dot(out), 0.0f) << "surface tension pulls a convex surface inward";
    // a = −(σ/m) κ n̂ in SI units: |a| = σ κ / m.
    EXPECT_NEAR(a[i].norm(), 0.05f / kMass * st.curvatures()[i], 1e-4f * a[i].norm());
  }
  EXPECT_EQ(surface, int(outer));
  // Lattice faces: the normal is the face normal.
  Cloud blk(block(8));
  std::vector<Vec3f> b(blk.x.size(), Vec3f::Zero());
  st.add_accelerations(blk.x, blk.id, blk.nb, st_params(), kDt, 6, b);
  for (std::size_t i = 0; i < blk.x.size(); ++i) {
    const Vec3f q = blk.x[i] / kD;
    if (std::lround(q.y()) == 7 && (q.array() > 1.5f).all() && (q.array() < 5.5f).all()) {
      EXPECT_GT(st.normals()[i].y(), 0.98f) << "top face at " << q.transpose();
    }
  }
}

TEST(SurfaceTension, ZeroSigmaAddsNothing) {
  Cloud cl(block(6));
  std::vector<Vec3f> a(cl.x.size(), Vec3f(1.0f, 2.0f, 3.0f));
  const auto before = a;
  SurfaceTension st;
  auto p = st_params();
  p.sigma = 0.0f;
  st.add_accelerations(cl.x, cl.id, cl.nb, p, kDt, 1, a);
  EXPECT_EQ(a, before);
  for (auto c : st.classes()) EXPECT_EQ(c, 0);
}

// The sample points of a particle are keyed on (id, step key), never on its index or the thread that runs it.
TEST(SurfaceTension, ResultsDependOnIdsAndStepKeyNotOnThreadsOrOrder) {
  std::size_t outer = 0;
  const std::vector<Vec3f> pts = shell_ball(5.0f * kD, 10.0f * kD, &outer);
  Cloud cl(pts);
  auto run = [&](const Cloud& c, std::uint64_t key, SurfaceTension& st) {
    std::vector<Vec3f> a(c.x.size(), Vec3f::Zero());
    st.add_accelerations(c.x, c.id, c.nb, st_params(), kDt, key, a);
    return a;
  };
  const int saved = omp_get_max_threads();
  SurfaceTension s1, s2, s3;
  omp_set_num_threads(1);
  const auto a1 = run(cl, 42, s1);
  omp_set_num_threads(std::max(2, saved));
  const auto a2 = run(cl, 42, s2);
  const auto a3 = run(cl, 43, s3);
  omp_set_num_threads(saved);
  ASSERT_EQ(a1.size(), a2.size());
  EXPECT_EQ(0, std::memcmp(a1.data(), a2.data(), a1.size() * sizeof(Vec3f))) << "1 vs 2 threads";
  EXPECT_NE(s1.raw_curvatures()[0], s3.raw_curvatures()[0]) << "another step draws other points";

  // Reversed order, same ids: per id the Monte-Carlo result is identical (coverage is an exact yes/no); the
  // smoothing sums neighbours in another order, so the final values agree to rounding.
  std::vector<Vec3f> rx(pts.rbegin(), pts.rend());
  std::vector<Index> rid(cl.id.rbegin(), cl.id.rend());
  Cloud rev(rx, rid);
  SurfaceTension s4;
  const auto a4 = run(rev, 42, s4);
  const std::size_t n = pts.size();
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t k = n - 1 - i;
    ASSERT_EQ(s1.classes()[i], s4.classes()[k]);
    ASSERT_EQ(s1.raw_curvatures()[i], s4.raw_curvatures()[k]) << i;
    ASSERT_EQ(s1.raw_normals()[i], s4.raw_normals()[k]) << i;
    ASSERT_NEAR((a1[i] - a4[k]).norm(), 0.0f, 1e-4f * (a1[i].norm() + 1e-6f)) << i;
  }
}

TEST(SurfaceTension, SampleCountIsSamplesPerSecondTimesTheStep) {
  EXPECT_EQ(surface_tension_samples(10000.0f, 1.0f / 120.0f), 83);
  EXPECT_EQ(surface_tension_samples(10000.0f, 1e-6f), 1);
  EXPECT_NE(surface_tension_step_key(0.0), surface_tension_step_key(1.0 / 120.0));
}

DragParams drag_params() {
  DragParams p;
  p.spacing = kD;
  p.mass = kMass;
  return p;
}

// Gissler et al. for one particle without neighbours, written out independently in double precision.
Vec3d lone_drag(const Vec3d& v) {
  const double pi = M_PI, d = kD, rho_l = 1000.0, rho_a = 1.2931, sigma = 0.0724, mu_l = 0.00102, mu_a = 0.00001845;
  const double L = std::cbrt(3.0 / (4.0 * pi)) * d;
  const double td = 2.0 * rho_l * L * L / (5.0 * mu_l);
  const double omega = std::sqrt(8.0 * sigma / (rho_l * L * L * L) - 1.0 / (td * td));
  const double arg = std::min(std::sqrt(td * td * omega * omega + 1.0) + td * omega, pi / 2.0);  // as SPlisHSPlasH
  const double t_max = 2.0 * (pi - std::atan(arg)) / omega;
  const double c_def = 1.0 - std::exp(-t_max / td) * (std::cos(omega * t_max) + std::sin(omega * t_max) / (omega * td));
  const Vec3d v_rel = -v;
  const double speed = v_rel.norm();
  const double y = std::min(1.0, speed * speed * (1.0 / 3.0) * rho_a * L * c_def / (sigma * 8.0 * 0.5));
  const double re = std::max(2.0 * rho_a * speed * L / mu_a, 0.2);
  const double cd_sphere = re <= 1000.0 ? 24.0 / re * (1.0 + std::pow(re, 2.0 / 3.0) / 6.0) : 0.424;
  const double cd = cd_sphere * (1.0 + 2.632 * y);
  const double area = pi * std::pow(L + 0.5 * L * y, 2.0);
  return 0.01 * 0.5 * rho_a * speed * v_rel * cd * area / (rho_l * d * d * d);
}

TEST(Drag, LoneDropletMatchesTheFormulaInSiUnits) {
  for (const Vec3f& v : {Vec3f(2.0f, 0.0f, 0.0f), Vec3f(0.0f, -0.01f, 0.005f), Vec3f(-1.0f, 4.0f, 0.5f)}) {
    Cloud cl({Vec3f::Zero(), Vec3f(1.0f, 1.0f, 1.0f)});  // two particles far apart: no neighbours
    const std::vector<Vec3f> vel{v, Vec3f::Zero()};
    std::vector<Vec3f> a(2, Vec3f::Zero());
    add_drag(cl.x, vel, cl.nb, drag_params(), a);
    const Vec3d want = lone_drag(v.cast<double>());
    EXPECT_NEAR((a[0].cast<double>() - want).norm(), 0.0, 1e-4 * want.norm()) << a[0].transpose() << " vs " << want.transpose();
    EXPECT_LT(a[0].dot(v), 0.0f);
    EXPECT_EQ(a[1], Vec3f::Zero()) << "a particle at rest feels no drag";
  }
}

TEST(Drag, OpposesTheVelocityIsOccludedInsideAndVanishesAtRest) {
  Cloud cl(block(6));
  const Vec3f u(0.6f, -1.5f, 0.3f);
  std::vector<Vec3f> v(cl.x.size(), u), a(cl.x.size(), Vec3f::Zero());
  v[0] = Vec3f::Zero();  // a corner particle at rest
  add_drag(cl.x, v, cl.nb, drag_params(), a);
  EXPECT_EQ(a[0], Vec3f::Zero());
  int pushed = 0;
  for (std::size_t i = 1; i < cl.x.size(); ++i) {
    if (a[i] == Vec3f::Zero()) continue;
    ++pushed;
    EXPECT_NEAR(a[i].normalized().dot(-u.normalized()), 1.0f, 1e-5f) << "antiparallel to v at particle " << i;
  }
  EXPECT_GT(pushed, 0);
  // Air drag on a whole block is tiny at s = 0.01 (METHOD.md §a.4): far below gravity.
  float largest = 0.0f;
  for (const auto& ai : a) largest = std::max(largest, ai.norm());
  EXPECT_LT(largest, 0.01f);
  // The leading faces (v̂ points out of them) are exposed; a particle with a neighbour straight ahead is not.
  Cloud line({Vec3f::Zero(), Vec3f(kD, 0.0f, 0.0f)});
  std::vector<Vec3f> lv(2, Vec3f(1.0f, 0.0f, 0.0f)), la(2, Vec3f::Zero());
  add_drag(line.x, lv, line.nb, drag_params(), la);
  EXPECT_EQ(la[0], Vec3f::Zero()) << "the trailing particle is shielded by the one ahead";
  EXPECT_LT(la[1].x(), 0.0f) << "the leading particle is exposed";
}

TEST(Drag, ZeroScaleAddsNothingAndThreadsDoNotMatter) {
  Cloud cl(block(14));
  std::vector<Vec3f> v(cl.x.size());
  for (std::size_t i = 0; i < v.size(); ++i) v[i] = Vec3f(std::sin(float(i)), std::cos(0.7f * float(i)), 0.3f);
  std::vector<Vec3f> a(cl.x.size(), Vec3f::Constant(0.5f));
  const auto before = a;
  auto p = drag_params();
  p.scale = 0.0f;
  add_drag(cl.x, v, cl.nb, p, a);
  EXPECT_EQ(a, before);
  const int saved = omp_get_max_threads();
  std::vector<Vec3f> a1(cl.x.size(), Vec3f::Zero()), a2 = a1;
  omp_set_num_threads(1);
  add_drag(cl.x, v, cl.nb, drag_params(), a1);
  omp_set_num_threads(std::max(2, saved));
  add_drag(cl.x, v, cl.nb, drag_params(), a2);
  omp_set_num_threads(saved);
  EXPECT_EQ(0, std::memcmp(a1.data(), a2.data(), a1.size() * sizeof(Vec3f)));
  EXPECT_NE(a1, std::vector<Vec3f>(a1.size(), Vec3f::Zero()));
}

// Records what the solver's add_accelerations hook sees: positions, velocities and a_ext of the sub-step.
class Capture final : public Controller {
 public:
  std::string_view name() const override { return "capture"; }
  void add_accelerations(const StepView& view, ParticleSet& p) override {
    x = p.position;
    v = p.velocity;
    a = p.acceleration;
    neighbors = view.fluid_neighbors;
  }
  std::vector<Vec3f> x, v, a;
  const core::NeighborList* neighbors = nullptr;
};

// The solver folds the drag's neighbour pass into its XSPH pass: the result is add_drag()'s.
TEST(Drag, SolverAddsTheSameDragAsTheStandalonePass) {
  SolverParams sp;
  sp.gravity = Vec3f::Zero();
  sp.surface_tension = 0.0f;
  sp.viscosity = 1e-30f;  // XSPH on (so the fused pass runs) but far below one ulp of the drag
  const Domain dom{Vec3f::Zero(), Vec3f::Constant(1.0f)};
  ParticleSet p;
  ASSERT_TRUE(fill_sources(std::vector<FluidSource>{{FluidSource::Shape::Box, Vec3f::Zero(), Vec3f::Constant(0.4f)}},
                           dom, sp.particle_radius, p).ok());
  for (std::size_t i = 0; i < p.size(); ++i)
    p.velocity[i] = Vec3f(std::sin(0.3f * float(i)), std::cos(0.7f * float(i)), 0.5f * std::sin(1.3f * float(i)));
  p.velocity[5] = Vec3f::Zero();
  PbfSolver solver(sp, dom);
  Capture cap;
  StageTimes times;
  solver.substep(p, 0.0, kDt, cap, times);
  ASSERT_NE(cap.neighbors, nullptr);
  DragParams dp;
  dp.spacing = sp.spacing();
  dp.mass = solver.particle_mass();
  std::vector<Vec3f> want(cap.x.size(), Vec3f::Zero());
  add_drag(cap.x, cap.v, *cap.neighbors, dp, want);
  int nonzero = 0;
  for (std::size_t i = 0; i < want.size(); ++i) {
    nonzero += want[i] != Vec3f::Zero();
    ASSERT_NEAR((cap.a[i] - want[i]).norm(), 0.0f, 1e-12f) << i << ": " << cap.a[i].transpose() << " vs "
                                                           << want[i].transpose();
  }
  EXPECT_GT(nonzero, int(want.size()) / 4);
}

// A cube of fluid in zero gravity: surface tension rounds it off (the corners come in) without blowing up.
// s_corr is off here: its repulsion has no cohesion to balance at a free surface without gravity (the density
// constraint is one-sided), so at r = 0.025 it slowly evaporates the cube with or without surface tension.
TEST(SurfaceTension, PullsAFreeCubeTowardsASphere) {
  auto corner_distance = [](const ParticleSet& p) {
    Vec3f c = Vec3f::Zero();
    for (const auto& x : p.position) c += x;
    c /= float(p.size());
    float r = 0.0f;
    for (const auto& x : p.position) r = std::max(r, (x - c).norm());
    return r;
  };
  for (float sigma : {0.05f, 0.0f}) {
    SolverParams sp;
    sp.gravity = Vec3f::Zero();
    sp.scorr_k = 0.0f;
    sp.surface_tension = sigma;
    const Domain dom{Vec3f::Constant(-1.0f), Vec3f::Constant(1.6f)};
    ParticleSet p;
    ASSERT_TRUE(fill_sources(std::vector<FluidSource>{{FluidSource::Shape::Box, Vec3f::Zero(), Vec3f::Constant(0.59f)}},
                             dom, sp.particle_radius, p).ok());
    ASSERT_EQ(p.size(), 1728u);
    const float start = corner_distance(p);
    PbfSolver solver(sp, dom);
    NoController none;
    double peak = 0.0;
    float low = start;  // the shape oscillates (little damping): track the smallest corner distance
    for (int f = 0; f < 45; ++f) {
      auto st = solver.advance(p, f / 60.0, 1.0 / 60.0, none);
      ASSERT_TRUE(st.has_value()) << st.error().message;
      peak = std::max(peak, st->max_speed);
      low = std::min(low, corner_distance(p));
    }
    const float end = corner_distance(p);
    std::printf("free cube, sigma %.2f: corner distance %.3f m, lowest %.3f, after 0.75 s %.3f, peak speed %.2f m/s\n",
                double(sigma), double(start), double(low), double(end), peak);
    if (sigma > 0.0f) {
      const float sphere = std::cbrt(3.0f * 1728.0f / (4.0f * float(M_PI))) * sp.spacing();
      EXPECT_LT(low, 0.8f * start) << "the corners come in (sphere radius " << sphere << ")";
      EXPECT_GT(low, 0.9f * sphere) << "but not through the sphere of the same volume";
      EXPECT_LT(end, 0.9f * start);
      EXPECT_LT(peak, 1.0) << "no blow-up";
    } else {
      EXPECT_GT(low, 0.97f * start) << "without surface tension nothing rounds the cube";
    }
  }
}

// The whole solver with both forces on (the defaults): bit-identical for 1 and 2 threads, and different from a
// run without them (so they are wired in).
TEST(SurfaceTension, SolverWithForcesIsBitIdenticalForOneAndTwoThreads) {
  auto run = [](int threads, float sigma, float drag) {
    SolverParams sp;
    sp.particle_radius = 0.02f;
    sp.surface_tension = sigma;
    sp.drag = drag;
    const Domain dom{Vec3f::Zero(), Vec3f(0.8f, 0.6f, 0.3f)};
    ParticleSet p;
    EXPECT_TRUE(fill_sources(std::vector<FluidSource>{{FluidSource::Shape::Box, Vec3f::Zero(), Vec3f(0.3f, 0.4f, 0.3f)}},
                             dom, sp.particle_radius, p).ok());
    const int saved = omp_get_max_threads();
    omp_set_num_threads(threads);
    PbfSolver solver(sp, dom);
    NoController none;
    for (int f = 0; f < 12; ++f) EXPECT_TRUE(solver.advance(p, f / 60.0, 1.0 / 60.0, none).has_value());
    omp_set_num_threads(saved);
    std::vector<Vec3f> x, v;
    std::vector<std::uint8_t> t;
    sorted_by_id(p, x, v, t);
    return std::make_pair(x, v);
  };
  SolverParams defaults;
  ASSERT_GT(defaults.surface_tension, 0.0f);
  ASSERT_GT(defaults.drag, 0.0f);
  const auto one = run(1, defaults.surface_tension, defaults.drag);
  const auto two = run(2, defaults.surface_tension, defaults.drag);
  ASSERT_EQ(one.first.size(), two.first.size());
  EXPECT_EQ(0, std::memcmp(one.first.data(), two.first.data(), one.first.size() * sizeof(Vec3f)));
  EXPECT_EQ(0, std::memcmp(one.second.data(), two.second.data(), one.second.size() * sizeof(Vec3f)));
  const auto plain = run(2, 0.0f, 0.0f);
  const auto drag_only = run(2, 0.0f, defaults.drag);
  EXPECT_NE(plain.first, one.first) << "surface tension and drag change the flow";
  EXPECT_NE(plain.second, drag_only.second) << "drag alone changes the flow";
}

}  // namespace
}  // namespace ff::sim
