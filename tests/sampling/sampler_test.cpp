// Samplers, sample elimination, control weights and the control PLY (sampling/samplers.h, weights.h).
// Fast cases only: small sets on procedural shapes. The quality family (bunny, vase, torus, ...) at
// realistic sizes is in sampler_quality_test.cpp (slow).
#include "sampling/control_io.h"
#include "sampling/sample_elimination.h"
#include "sampling/samplers.h"
#include "sampling/weights.h"
#include "support/shapes.h"
#include "support/test_support.h"

#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <random>

namespace ff::sampling {
namespace {

float min_pair_distance(const std::vector<Vec3f>& x) {
  float best = std::numeric_limits<float>::max();
  for (std::size_t i = 0; i < x.size(); ++i)
    for (std::size_t j = i + 1; j < x.size(); ++j) best = std::min(best, (x[i] - x[j]).norm());
  return best;
}

TEST(SampleElimination, KeepsTheRequestedCountAndSpreadsBetterThanRandom) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::vector<Vec3f> cand(3000);
  for (auto& p : cand) p = Vec3f(u(rng), u(rng), u(rng));
  EliminationParams ep;
  ep.d_max = static_cast<float>(2.0 * volume_r_max(1.0, 1000));
  const auto keep = eliminate_samples(cand, 1000, ep);
  ASSERT_EQ(keep.size(), 1000u);
  EXPECT_TRUE(std::is_sorted(keep.begin(), keep.end()));
  EXPECT_EQ(std::adjacent_find(keep.begin(), keep.end()), keep.end());
  std::vector<Vec3f> kept, first;
  for (Index k : keep) kept.push_back(cand[k]);
  first.assign(cand.begin(), cand.begin() + 1000);
  // Random points of this density come as close as ~0.01; eliminated ones keep well apart.
  EXPECT_GT(min_pair_distance(kept), 3.0f * min_pair_distance(first));
  EXPECT_GT(min_pair_distance(kept), 0.5f * ep.d_max * 0.5f);
}

TEST(Weights, IsolatedSampleHasWeightOneAndPhiRange) {
  ControlSet s;
  s.spacing = 0.1f;
  s.resize(2);
  s.position = {Vec3f(0, 0, 0), Vec3f(10, 0, 0)};  // far apart: both isolated
  std::vector<float> depth(2, 0.0f);
  ASSERT_TRUE(compute_weights(s, depth, {}).ok());
  EXPECT_FLOAT_EQ(s.weight[0], 1.0f);
  EXPECT_FLOAT_EQ(s.weight[1], 1.0f);
  for (float p : s.phi) {
    EXPECT_GE(p, 0.05f - 1e-6f);
    EXPECT_LE(p, 1.05f + 1e-6f);
  }
}

TEST(Weights, CornersWeighMoreThanInteriorAndInteriorDensityIsCalibrated) {
  // A 16³ cubic lattice: the kernel sums fall towards faces, edges and corners.
  ControlSet s;
  const float d = 0.05f;
  s.spacing = d;
  std::vector<float> depth;
  for (int k = 0; k < 16; ++k)
    for (int j = 0; j < 16; ++j)
      for (int i = 0; i < 16; ++i) {
        s.position.emplace_back(float(i) * d, float(j) * d, float(k) * d);
        const int m = std::min({i, j, k, 15 - i, 15 - j, 15 - k});
        depth.push_back((float(m) + 0.5f) * d);
      }
  s.resize(s.position.size());
  ASSERT_TRUE(compute_weights(s, depth, {}).ok());
  const Vec3f corner(0, 0, 0), centre = Vec3f::Constant(7.5f * d);
  float w_corner = 0, w_centre = 1e9f, phi_lo = 1e9f, phi_hi = -1e9f;
  for (std::size_t i = 0; i < s.size(); ++i) {
    if ((s.position[i] - corner).norm() < 1e-6f) w_corner = s.weight[i];
    if ((s.position[i] - centre).norm() < 0.9f * d) w_centre = std::min(w_centre, s.weight[i]);
    phi_lo = std::min(phi_lo, s.phi[i]);
    phi_hi = std::max(phi_hi, s.phi[i]);
  }
  // 0.088 vs 0.0245 at H_c = 4d (3.6×), 0.167 vs 0.058 at 3d (2.9×): a corner sees ~1/8 of a full support.
  EXPECT_GT(w_corner, 2.5f * w_centre);
  EXPECT_NEAR(phi_lo, 0.05f, 1e-5f);
  EXPECT_NEAR(phi_hi, 1.05f, 1e-5f);
  // x̄ of a symmetric set is its centre.
  EXPECT_LT((s.centre - centre).norm(), 1e-4f);
  // Interior ρ_c equals the kernel-sum density of a resting fluid lattice (here: the same lattice).
  const double rho_fluid = lattice_density(d, WeightParams{}.support_factor * d, 1000.0f);
  for (std::size_t i = 0; i < s.size(); ++i) {
    if ((s.position[i] - centre).norm() < 0.9f * d) {
      EXPECT_NEAR(s.density[i], rho_fluid, 1e-3 * rho_fluid);
    }
  }
}

TEST(Samplers, VoxelSamplesOfABoxAreTheLatticeInside) {
  const auto mesh = test::box(Vec3f(0.5f, 0.25f, 0.25f));
  SamplingParams p;
  p.method = Method::Voxel;
  p.spacing = 0.1f;
  SampleReport rep;
  auto set = sample_target(mesh, p, 3, &rep);
  ASSERT_TRUE(set.has_value()) << set.error().message;
  EXPECT_EQ(set->size(), 10u * 5u * 5u);
  EXPECT_EQ(set->target, 3);
  EXPECT_EQ(rep.method, Method::Voxel);
  for (const auto& x : set->position) EXPECT_LT((x.cwiseAbs() - Vec3f(0.5f, 0.25f, 0.25f)).maxCoeff(), 0.0f);
}

// The solid's cells at a spacing: a slab 4.9 spacings thick reads 4.9 cells across, where the lattice points inside
// are 4 layers; a ball reads its volume.
TEST(Samplers, LatticeCellsCountThePartsOfCellsTheSolidCovers) {
  const float d = 0.01f;
  for (const float t : {4.9f, 3.3f, 1.6f}) {
    auto slab = MeshField::build(test::box(Vec3f(0.3f, 0.5f * t * d, 0.2f)));
    ASSERT_TRUE(slab.has_value());
    const double cells = lattice_cells(*slab, d).cells(), exact = 0.6 * 0.4 * t * d / (double(d) * d * d);
    EXPECT_NEAR(cells, exact, 0.02 * exact) << t << " spacings";
    EXPECT_LE(double(voxel_samples(*slab, d).size()), std::floor(t) / t * exact * 1.001);  // whole layers only
  }
  auto ball = MeshField::build(test::uv_sphere(0.2f, 64));
  ASSERT_TRUE(ball.has_value());
  const auto cells = lattice_cells(*ball, d);
  EXPECT_NEAR(cells.cells() * d * d * d, ball->volume(), 0.01 * ball->volume());
  for (std::size_t i = 0; i < cells.share.size(); ++i) {
    EXPECT_GT(cells.share[i], 0.0f);
    EXPECT_LE(cells.share[i], 1.0f);
  }
}

TEST(Samplers, BlueNoiseSphereIsSpreadInsideAndDeterministic) {
  const auto mesh = test::uv_sphere(0.5f, 48);
  SamplingParams p;
  p.spacing = 0.08f;
  p.relax_steps = 40;
  SampleReport rep;
  auto a = sample_target(mesh, p, 0, &rep);
  ASSERT_TRUE(a.has_value()) << a.error().message;
  const double expect = (4.0 / 3.0) * M_PI * 0.125 / (0.08 * 0.08 * 0.08);
  EXPECT_NEAR(double(a->size()), expect, 0.05 * expect);
  for (const auto& x : a->position) EXPECT_LE(x.norm() - 0.5f, 0.25f * 0.08f);
  EXPECT_GE(min_pair_distance(a->position), 0.8f * 0.08f);
  auto b = sample_target(mesh, p);
  ASSERT_TRUE(b.has_value());
  EXPECT_EQ(a->position, b->position) << "same seed, same samples";
  p.seed = 2;
  auto c = sample_target(mesh, p);
  ASSERT_TRUE(c.has_value());
  EXPECT_NE(a->position, c->position);
}

TEST(Samplers, BlueNoiseIsIndependentOfTheThreadCount) {
  const auto mesh = test::torus(0.5f, 0.2f, 48, 24);
  SamplingParams p;
  p.auto_count = 4000;  // above the serial cut-off of the parallel loops
  p.relax_steps = 20;
  const int saved = omp_get_max_threads();
  omp_set_num_threads(1);
  auto a = sample_target(mesh, p);
  omp_set_num_threads(std::max(2, saved));
  auto b = sample_target(mesh, p);
  omp_set_num_threads(saved);
  ASSERT_TRUE(a.has_value() && b.has_value());
  EXPECT_EQ(a->position, b->position);
  EXPECT_EQ(a->weight, b->weight);
  EXPECT_EQ(a->density, b->density);
}

TEST(Samplers, OpenSheetBecomesAShellWithAWarning) {
  const auto mesh = test::plane_sheet(8, 1.0f);
  SamplingParams p;
  p.spacing = 0.1f;
  SampleReport rep;
  auto set = sample_target(mesh, p, 0, &rep);
  ASSERT_TRUE(set.has_value()) << set.error().message;
  EXPECT_EQ(rep.method, Method::Surface);
  ASSERT_EQ(rep.warnings.size(), 1u);
  EXPECT_NE(rep.warnings[0].find("encloses no volume"), std::string::npos);
  const double expect = 1.0 / (0.5 * std::sqrt(3.0) * 0.01);
  EXPECT_NEAR(double(set->size()), expect, 0.05 * expect);
}

TEST(Samplers, SparseOptionsDropSamples) {
  const auto mesh = test::box(Vec3f::Constant(0.5f));
  SamplingParams p;
  p.method = Method::Voxel;
  p.spacing = 0.1f;
  p.sparse.drop_boxes.push_back({Vec3f(-1, -1, -1), Vec3f(0, 1, 1)});
  SampleReport rep;
  auto set = sample_target(mesh, p, 0, &rep);
  ASSERT_TRUE(set.has_value());
  EXPECT_EQ(set->size(), 500u);
  EXPECT_EQ(rep.dropped, 500u);
  for (const auto& x : set->position) EXPECT_GT(x.x(), 0.0f);
  p.sparse.drop_boxes.clear();
  p.sparse.drop_fraction = 0.3f;
  set = sample_target(mesh, p, 0, &rep);
  ASSERT_TRUE(set.has_value());
  EXPECT_NEAR(double(set->size()), 700.0, 60.0);
}

TEST(Samplers, TooManySamplesIsAClearError) {
  const auto mesh = test::box(Vec3f::Constant(1.0f));
  SamplingParams p;
  p.spacing = 0.001f;  // 8e9 samples
  auto set = sample_target(mesh, p);
  ASSERT_FALSE(set.has_value());
  EXPECT_NE(set.error().message.find("more than the limit of 20000000"), std::string::npos) << set.error().message;
  EXPECT_NE(set.error().message.find("about 7999"), std::string::npos) << set.error().message;  // 8 m³ / 1 mm³
}

TEST(Samplers, ClosedMeshWithoutVolumeIsAClearError) {
  // A tetrahedron whose four corners lie in one plane: closed (every edge has two faces), no face
  // degenerate, zero volume.
  io::TriangleMesh flat;
  flat.vertices = {Vec3f(0, 0, 0), Vec3f(1, 0, 0), Vec3f(1, 0, 1), Vec3f(0, 0, 1)};
  flat.triangles = {{0, 1, 2}, {0, 2, 3}, {0, 3, 1}, {1, 3, 2}};
  auto set = sample_target(flat, SamplingParams{});
  ASSERT_FALSE(set.has_value());
  EXPECT_NE(set.error().message.find("encloses no volume"), std::string::npos) << set.error().message;
}

TEST(Samplers, EmptyMeshIsAClearError) {
  io::TriangleMesh empty;
  auto set = sample_target(empty, SamplingParams{});
  ASSERT_FALSE(set.has_value());
  EXPECT_FALSE(set.error().message.empty());
}

TEST(ControlIo, RoundTripIsExact) {
  const auto mesh = test::box(Vec3f::Constant(0.3f));
  SamplingParams p;
  p.method = Method::Voxel;
  p.spacing = 0.1f;
  auto set = sample_target(mesh, p, 7);
  ASSERT_TRUE(set.has_value());
  const auto dir = test::temp_dir("controls");
  const auto file = dir / "c.ply";
  ASSERT_TRUE(write_controls_ply(file, *set, 0x1234).ok());
  std::uint64_t key = 0;
  auto back = read_controls_ply(file, &key);
  ASSERT_TRUE(back.has_value()) << back.error().message;
  EXPECT_EQ(key, 0x1234u);
  EXPECT_EQ(back->position, set->position);
  EXPECT_EQ(back->weight, set->weight);
  EXPECT_EQ(back->phi, set->phi);
  EXPECT_EQ(back->density, set->density);
  EXPECT_EQ(back->mass, set->mass);
  EXPECT_EQ(back->support, set->support);
  EXPECT_EQ(back->spacing, set->spacing);
  EXPECT_EQ(back->centre, set->centre);
  EXPECT_EQ(back->target, 7);
}

}  // namespace
}  // namespace ff::sampling
