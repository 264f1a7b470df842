// Surface reconstruction (src/surface): the mesh check against known meshes, marching cubes on random fields
// (every case and ambiguous face), and the whole pipeline on particles filling an analytic sphere and torus,
// measured against the true surface. Sizes are small (~2k particles) so the suite runs under ASan.
#include "surface/cluster_reduce.h"
#include "surface/marching_cubes.h"
#include "surface/mc_table.h"
#include "surface/mesh_check.h"
#include "surface/reconstruct.h"
#include "surface/smooth.h"
#include "surface/sparse_field.h"
#include "surface/surface_shapes.h"
#include "support/shapes.h"

#include <Eigen/Geometry>

#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>
#include <limits>
#include <random>

namespace ff::surface {
namespace {

constexpr float kD = 0.1f;  // particle spacing d, m

// --- check_mesh ------------------------------------------------------------------------------------------------------

TEST(MeshCheck, ClosedShapesPassWithTheirGenus) {
  const MeshCheck s = check_mesh(test::uv_sphere(1.0f, 24));
  EXPECT_TRUE(s.ok()) << s.summary();
  EXPECT_EQ(s.components, 1u);
  EXPECT_EQ(s.genus, 0);
  EXPECT_EQ(s.euler, 2);
  EXPECT_NEAR(s.volume, 4.0 / 3.0 * 3.14159265, 0.15);
  const MeshCheck t = check_mesh(test::torus(1.0f, 0.3f, 32, 16));
  EXPECT_TRUE(t.ok()) << t.summary();
  EXPECT_EQ(t.genus, 1);
  EXPECT_EQ(t.euler, 0);
  const MeshCheck two = check_mesh(
      test::merge(test::uv_sphere(1.0f, 12), test::translate(test::torus(1.0f, 0.3f, 16, 8), Vec3f(5, 0, 0))));
  EXPECT_TRUE(two.ok()) << two.summary();
  EXPECT_EQ(two.components, 2u);
  EXPECT_EQ(two.genus, 1);
}

TEST(MeshCheck, FindsEachDefect) {
  const MeshCheck flipped = check_mesh(test::flip(test::uv_sphere(1.0f, 16)));
  EXPECT_TRUE(flipped.watertight() && flipped.manifold() && flipped.oriented());
  EXPECT_FALSE(flipped.outward());
  EXPECT_FALSE(flipped.ok());

  const MeshCheck hole = check_mesh(test::sphere_with_hole(3));
  EXPECT_FALSE(hole.watertight());
  EXPECT_GT(hole.boundary_edges, 0u);
  EXPECT_EQ(hole.genus, -1);

  io::TriangleMesh one_flipped = test::uv_sphere(1.0f, 16);
  std::swap(one_flipped.triangles[5][1], one_flipped.triangles[5][2]);
  const MeshCheck mis = check_mesh(one_flipped);
  EXPECT_TRUE(mis.watertight() && mis.manifold());
  EXPECT_EQ(mis.misoriented_edges, 3u);
  EXPECT_FALSE(mis.ok());

  io::TriangleMesh dup = test::uv_sphere(1.0f, 16);
  dup.triangles.push_back(dup.triangles[7]);
  const MeshCheck d = check_mesh(dup);
  EXPECT_FALSE(d.manifold());
  EXPECT_EQ(d.nonmanifold_edges, 3u);

  // Two tetrahedra sharing one vertex: every edge is fine, the shared vertex is a bow-tie.
  io::TriangleMesh bow;
  bow.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {-1, 0, 0}, {0, -1, 0}, {0, 0, -1}};
  bow.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}, {0, 5, 4}, {0, 4, 6}, {0, 6, 5}, {4, 5, 6}};
  const MeshCheck b = check_mesh(bow);
  EXPECT_TRUE(b.watertight());
  EXPECT_EQ(b.nonmanifold_edges, 0u);
  EXPECT_EQ(b.nonmanifold_vertices, 1u);
  EXPECT_FALSE(b.ok());

  io::TriangleMesh degenerate = test::uv_sphere(1.0f, 16);
  degenerate.vertices[degenerate.triangles[3][0]] = degenerate.vertices[degenerate.triangles[3][1]];
  EXPECT_GT(check_mesh(degenerate).degenerate_triangles, 0u);

  io::TriangleMesh bad_index = test::uv_sphere(1.0f, 8);
  bad_index.triangles[0][0] = 100000;
  EXPECT_EQ(check_mesh(bad_index).invalid_triangles, 1u);

  io::TriangleMesh unused = test::uv_sphere(1.0f, 8);
  unused.vertices.emplace_back(9, 9, 9);
  EXPECT_EQ(check_mesh(unused).unreferenced_vertices, 1u);
  EXPECT_TRUE(check_mesh(io::TriangleMesh{}).ok());
}

// --- marching cubes on random fields
// ----------------------------------------------------------------------------------

// One block whose outer shell of nodes is outside and whose inside nodes are random: every cube case and every
// ambiguous face shows up within a few blocks.
SparseField random_block(std::mt19937& rng, bool ties) {
  SparseField f;
  f.origin = Vec3d::Zero();
  f.cell = 1.0;
  f.iso = 0.5f;
  f.block_dims = {3, 3, 3};
  f.keys = {f.block_key(1, 1, 1)};
  std::vector<float> v(SparseField::kNodesPerBlock, 0.0f);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::uniform_int_distribution<int> q(0, 2);
  for (int k = 1; k < 8; ++k)
    for (int j = 1; j < 8; ++j)
      for (int i = 1; i < 8; ++i) v[std::size_t(SparseField::local(i, j, k))] = ties ? 0.5f * float(q(rng)) : u(rng);
  f.values = {v};
  return f;
}

TEST(MarchingCubes, TableCoversEveryCaseWithClosedLoops) {
  const McTable& t = McTable::get();
  EXPECT_EQ(t.cube(0, 0).triangle_count, 0);
  EXPECT_EQ(t.cube(255, 0).triangle_count, 0);
  EXPECT_EQ(t.cube(1, 0).triangle_count, 1);
  for (int m = 1; m < 255; ++m)
    for (int c = 0; c < (1 << t.ambiguous_count(m)); ++c) {
      const CubeTriangulation& ct = t.cube(m, c);
      // Every crossed edge carries a vertex that some triangle uses, and no other edge does.
      int used = 0;
      for (int k = 0; k < ct.triangle_count; ++k)
        for (const auto r : ct.triangles[std::size_t(k)])
          if (r < 12) used |= 1 << r;
      int crossed = 0;
      for (int e = 0; e < 12; ++e) {
        const CubeEdge ce = McTable::edge(e);
        if (((m >> ce.c0) & 1) != ((m >> ce.c1) & 1)) crossed |= 1 << e;
      }
      ASSERT_EQ(used, crossed) << "mask " << m << " centres " << c;
    }
}

TEST(MarchingCubes, RandomFieldsGiveClosedManifoldOutwardMeshes) {
  std::mt19937 rng(7);
  std::size_t centres = 0, triangles = 0;
  for (int trial = 0; trial < 60; ++trial) {
    const SparseField f = random_block(rng, trial % 3 == 2);
    auto mc = marching_cubes(f);
    ASSERT_TRUE(mc.has_value()) << mc.error().message;
    const MeshCheck c = check_mesh(mc->mesh);
    // Random fields enclose bubbles: their walls are wound inward, as they should be.
    ASSERT_TRUE(c.ok_allowing_cavities()) << "trial " << trial << ": " << c.summary();
    ASSERT_EQ(mc->cluster.size(), mc->mesh.vertices.size());
    centres += mc->centre_vertices;
    triangles += c.triangles;
  }
  EXPECT_GT(triangles, 10000u);
  EXPECT_GT(centres, 0u);  // the rare loops that need a centre vertex were exercised too
}

TEST(ClusterReduce, RandomFieldsStayClosedAndManifold) {
  std::mt19937 rng(11);
  for (int trial = 0; trial < 30; ++trial) {
    auto mc = marching_cubes(random_block(rng, false));
    ASSERT_TRUE(mc.has_value());
    ClusterStats cs;
    const io::TriangleMesh r = cluster_reduce(mc->mesh, mc->cluster, kNoCluster, {}, &cs);
    const MeshCheck c = check_mesh(r);
    ASSERT_TRUE(c.ok_allowing_cavities()) << "trial " << trial << ": " << c.summary();
    EXPECT_LE(r.triangles.size(), mc->mesh.triangles.size());
  }
}

// --- the pipeline on analytic shapes
// ----------------------------------------------------------------------------------

using Shape = test::AnalyticShape;
const Vec3f kCentre = test::kShapeCentre;
Shape sphere_shape() { return test::analytic_sphere(kD); }
Shape torus_shape() { return test::analytic_torus(kD); }

SurfaceParams plain_mc() {
  SurfaceParams p;
  p.smoothing_passes = 0;
  p.reduction = Reduction::None;
  p.decimate_error = 0.0f;
  p.max_triangles = 0;
  return p;
}

class OnAnalyticShapes : public ::testing::TestWithParam<Shape (*)()> {};

TEST_P(OnAnalyticShapes, ReconstructsAClosedOutwardMeshOfTheRightGenusNearTheTrueSurface) {
  const Shape s = GetParam()();
  SurfaceStats st;
  auto mesh = reconstruct(s.particles, kD, SurfaceParams{}, &st);
  ASSERT_TRUE(mesh.has_value()) << mesh.error().message;
  const MeshCheck c = check_mesh(*mesh);
  EXPECT_TRUE(c.watertight()) << s.name << ": " << c.summary();
  EXPECT_TRUE(c.manifold()) << s.name << ": " << c.summary();
  EXPECT_TRUE(c.oriented() && c.outward()) << s.name << ": " << c.summary();
  EXPECT_TRUE(c.no_degenerate()) << s.name << ": " << c.summary();
  EXPECT_EQ(c.components, 1u) << s.name;
  EXPECT_EQ(c.genus, s.genus) << s.name;
  EXPECT_EQ(st.check.ok(), true);
  EXPECT_FALSE(st.smoothing_undone || st.reduction_undone) << s.name;
  const auto dist = test::surface_distances(*mesh, s.sdf, s.truth);
  EXPECT_LE(dist.mesh_max, 0.5f * kD) << s.name << ": a vertex is off the true surface";
  EXPECT_LE(dist.surface_max, 0.5f * kD) << s.name << ": part of the true surface is not covered";
  std::printf(
      "[ %s ] %zu particles: MC %zu triangles -> %zu reduced -> %zu final; mesh off surface max %.3f d "
      "mean %.3f d; surface to mesh max %.3f d mean %.3f d\n",
      s.name, s.particles.size(), st.mc_triangles, st.reduced_triangles, mesh->triangles.size(), dist.mesh_max / kD,
      dist.mesh_mean / kD, dist.surface_max / kD, dist.surface_mean / kD);
}

TEST_P(OnAnalyticShapes, PlainMarchingCubesIsAlsoCloseAndClosed) {
  const Shape s = GetParam()();
  auto mesh = reconstruct(s.particles, kD, plain_mc());
  ASSERT_TRUE(mesh.has_value()) << mesh.error().message;
  const MeshCheck c = check_mesh(*mesh);
  EXPECT_TRUE(c.ok()) << c.summary();
  EXPECT_EQ(c.genus, s.genus);
  const auto dist = test::surface_distances(*mesh, s.sdf, s.truth);
  EXPECT_LE(dist.mesh_max, 0.5f * kD) << s.name;
  EXPECT_LE(dist.surface_max, 0.5f * kD) << s.name;
}

TEST_P(OnAnalyticShapes, ReductionAndDecimationCutTrianglesByFortyPercentAtNoLossOfAccuracy) {
  const Shape s = GetParam()();
  auto mc = reconstruct(s.particles, kD, plain_mc());
  auto full = reconstruct(s.particles, kD, SurfaceParams{});
  ASSERT_TRUE(mc.has_value() && full.has_value());
  EXPECT_LE(double(full->triangles.size()), 0.6 * double(mc->triangles.size()))
      << s.name << ": " << full->triangles.size() << " vs " << mc->triangles.size() << " marching-cubes triangles";
  const auto a = test::surface_distances(*mc, s.sdf, s.truth);
  const auto b = test::surface_distances(*full, s.sdf, s.truth);
  // Equal or better symmetric distance to the true surface, at worst (Hausdorff: mesh to surface and surface to
  // mesh) and on average (the mean of the two directions, the mesh side weighted by area). "Equal" allows
  // 0.01 d at worst and 0.005 d on average: the distances are set by the field (up to ~0.4 d here, the lattice
  // cannot place the surface better than ±0.5 d), and the stages move them by about a thousandth of d either way.
  const float hausdorff_mc = std::max(a.mesh_max, a.surface_max), hausdorff = std::max(b.mesh_max, b.surface_max);
  const float mean_mc = 0.5f * (a.mesh_mean + a.surface_mean), mean = 0.5f * (b.mesh_mean + b.surface_mean);
  EXPECT_LE(hausdorff, hausdorff_mc + 0.01f * kD) << s.name;
  EXPECT_LE(mean, mean_mc + 0.005f * kD) << s.name;
  std::printf(
      "[ %s ] MC %zu triangles: Hausdorff %.3f d, mean %.3f d; final %zu triangles: Hausdorff %.3f d, mean "
      "%.3f d\n",
      s.name, mc->triangles.size(), hausdorff_mc / kD, mean_mc / kD, full->triangles.size(), hausdorff / kD, mean / kD);
}

TEST_P(OnAnalyticShapes, SameMeshForAnyThreadCount) {
  const Shape s = GetParam()();
  const int saved = omp_get_max_threads();
  omp_set_num_threads(1);
  auto a = reconstruct(s.particles, kD, SurfaceParams{});
  omp_set_num_threads(3);
  auto b = reconstruct(s.particles, kD, SurfaceParams{});
  omp_set_num_threads(saved);
  ASSERT_TRUE(a.has_value() && b.has_value());
  ASSERT_EQ(a->vertices.size(), b->vertices.size());
  ASSERT_EQ(a->triangles, b->triangles);
  for (std::size_t i = 0; i < a->vertices.size(); ++i) ASSERT_EQ(a->vertices[i], b->vertices[i]) << i;
}

TEST_P(OnAnalyticShapes, TriangleBudgetHolds) {
  const Shape s = GetParam()();
  SurfaceParams p;
  p.max_triangles = 600;
  SurfaceStats st;
  auto mesh = reconstruct(s.particles, kD, p, &st);
  ASSERT_TRUE(mesh.has_value());
  EXPECT_LE(mesh->triangles.size(), 600u);
  EXPECT_TRUE(st.budget_met);
  const MeshCheck c = check_mesh(*mesh);
  EXPECT_TRUE(c.ok()) << c.summary();
  EXPECT_EQ(c.genus, s.genus);
}

TEST(Reconstruct, AnUnreachableBudgetKeepsTheLastGoodMesh) {
  // No closed genus-1 mesh has fewer than 14 triangles: the simplifier must fail to reach 8 without breaking the
  // torus, and the last clean mesh stands.
  const Shape s = torus_shape();
  SurfaceParams p;
  p.max_triangles = 8;
  SurfaceStats st;
  auto mesh = reconstruct(s.particles, kD, p, &st);
  ASSERT_TRUE(mesh.has_value());
  EXPECT_FALSE(st.budget_met);
  EXPECT_GE(mesh->triangles.size(), 14u);
  const MeshCheck c = check_mesh(*mesh);
  EXPECT_TRUE(c.ok()) << c.summary();
  EXPECT_EQ(c.genus, 1);
}

INSTANTIATE_TEST_SUITE_P(Surface, OnAnalyticShapes, ::testing::Values(&sphere_shape, &torus_shape));

// --- random clouds and bad input -------------------------------------------------------------------------------------

TEST(Reconstruct, RandomCloudsAlwaysGiveACheckedMesh) {
  std::mt19937 rng(5);
  std::normal_distribution<float> n(0.0f, 1.0f);
  for (int trial = 0; trial < 6; ++trial) {
    // Clumps of different sizes and some spray: thin necks, holes and droplets for every stage to survive.
    std::vector<Vec3f> p;
    for (int b = 0; b < 5; ++b) {
      const Vec3f c(2.0f * n(rng), 2.0f * n(rng), 2.0f * n(rng));
      const float r = 0.5f + 0.4f * std::abs(n(rng));
      for (int i = 0; i < 150; ++i) p.push_back(kD * (c + r * Vec3f(n(rng), n(rng), n(rng))) * 4.0f);
    }
    SurfaceParams params;
    params.max_triangles = 500;
    SurfaceStats st;
    auto mesh = reconstruct(p, kD, params, &st);
    ASSERT_TRUE(mesh.has_value()) << mesh.error().message;
    const MeshCheck c = check_mesh(*mesh);
    EXPECT_TRUE(c.ok()) << "trial " << trial << ": " << c.summary();
    EXPECT_EQ(c.summary(), st.check.summary());
  }
}

TEST(Reconstruct, BubblesAreDroppedUnlessAskedFor) {
  // A hollow ball: a sphere of radius 8d with a concentric hole of radius 4d (vacuum inside the fluid).
  const float r = 8.0f * kD;
  auto outer = test::sphere_sdf(kCentre, r), inner = test::sphere_sdf(kCentre, 4.0f * kD);
  const auto p = test::lattice_inside([&](const Vec3f& x) { return std::max(outer(x), -inner(x)); },
                                      kCentre - Vec3f::Constant(r), kCentre + Vec3f::Constant(r), kD);
  auto dropped = reconstruct(p, kD, SurfaceParams{});
  ASSERT_TRUE(dropped.has_value());
  const MeshCheck a = check_mesh(*dropped);
  EXPECT_TRUE(a.ok()) << a.summary();
  EXPECT_EQ(a.components, 1u);
  SurfaceParams keep;
  keep.remove_cavities = false;
  SurfaceStats st;
  auto kept = reconstruct(p, kD, keep, &st);
  ASSERT_TRUE(kept.has_value()) << kept.error().message;
  const MeshCheck b = check_mesh(*kept);
  EXPECT_TRUE(b.ok_allowing_cavities()) << b.summary();
  EXPECT_EQ(b.components, 2u);
  EXPECT_EQ(b.inward_components, 1u);
  EXPECT_LT(b.volume, a.volume);  // the bubble's volume is subtracted
  EXPECT_GT(st.decimate_passes, 0u);
}

TEST(Reconstruct, DropletsBelowTheMinimumVolumeAreDropped) {
  auto clump = [](int n, const Vec3f& at) {
    std::vector<Vec3f> p;
    for (int k = 0; k < n; ++k)
      for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) p.push_back(at + kD * Vec3f(float(i), float(j), float(k)));
    return p;
  };
  // A 3³ clump is kept (the parameter doc promises it), a 2³ one is spray; both far from each other.
  std::vector<Vec3f> p = clump(3, Vec3f::Zero());
  const auto spray = clump(2, Vec3f(2.0f, 0.0f, 0.0f));
  p.insert(p.end(), spray.begin(), spray.end());
  SurfaceStats st;
  auto mesh = reconstruct(p, kD, SurfaceParams{}, &st);
  ASSERT_TRUE(mesh.has_value());
  const MeshCheck c = check_mesh(*mesh);
  EXPECT_TRUE(c.ok()) << c.summary();
  EXPECT_EQ(c.components, 1u);
  EXPECT_GT(c.volume, 8.0 * kD * kD * kD);
  EXPECT_LT(mesh->bounds().max.x(), 1.0f);  // the kept one is the 3³ clump
  SurfaceParams keep_all;
  keep_all.min_component_volume = 0.0f;
  auto all = reconstruct(p, kD, keep_all);
  ASSERT_TRUE(all.has_value());
  EXPECT_EQ(check_mesh(*all).components, 2u);
}

TEST(Reconstruct, SparseParticlesGiveAnEmptyMeshNotAnError) {
  const std::vector<Vec3f> p = {{0, 0, 0}, {1, 0, 0}};
  SurfaceStats st;
  auto mesh = reconstruct(p, kD, SurfaceParams{}, &st);
  ASSERT_TRUE(mesh.has_value()) << mesh.error().message;
  EXPECT_TRUE(mesh->triangles.empty());
  EXPECT_LT(st.max_field, SurfaceParams{}.iso);
}

TEST(Reconstruct, BadInputIsAClearError) {
  const std::vector<Vec3f> none;
  auto e = reconstruct(none, kD, SurfaceParams{});
  ASSERT_FALSE(e.has_value());
  EXPECT_EQ(e.error().kind, Error::Kind::Input);
  EXPECT_NE(e.error().message.find("no particles"), std::string::npos);

  std::vector<Vec3f> p =
      test::lattice_inside(test::sphere_sdf(Vec3f::Zero(), 0.3f), Vec3f::Constant(-0.3f), Vec3f::Constant(0.3f), kD);
  p[7].y() = std::numeric_limits<float>::quiet_NaN();
  auto nan = reconstruct(p, kD, SurfaceParams{});
  ASSERT_FALSE(nan.has_value());
  EXPECT_EQ(nan.error().kind, Error::Kind::Input);
  EXPECT_NE(nan.error().message.find("particle 7"), std::string::npos) << nan.error().message;
  p[7].y() = std::numeric_limits<float>::infinity();
  EXPECT_FALSE(reconstruct(p, kD, SurfaceParams{}).has_value());
  p[7].y() = 0.0f;

  for (const float s : {0.0f, -1.0f, std::numeric_limits<float>::quiet_NaN()}) {
    auto r = reconstruct(p, s, SurfaceParams{});
    ASSERT_FALSE(r.has_value());
    EXPECT_EQ(r.error().kind, Error::Kind::Param);
  }
  SurfaceParams bad;
  bad.kernel_radius = 6.0f;  // > 8 cells of 0.5 d
  bad.cell_size = 0.5f;
  EXPECT_FALSE(bad.validate().ok());
  EXPECT_FALSE(reconstruct(p, kD, bad).has_value());
  bad = SurfaceParams{};
  bad.iso = std::numeric_limits<float>::quiet_NaN();
  EXPECT_FALSE(bad.validate().ok());
  bad = SurfaceParams{};
  bad.smoothing_beta = 1.5f;
  EXPECT_NE(bad.validate().error().message.find("smoothing_beta"), std::string::npos);
  EXPECT_TRUE(SurfaceParams{}.validate().ok());

  // A cloud too wide for the grid is refused, not allocated.
  std::vector<Vec3f> wide = {{0, 0, 0}, {1e6f, 0, 0}};
  auto w = reconstruct(wide, 1e-3f, SurfaceParams{});
  ASSERT_FALSE(w.has_value());
  EXPECT_EQ(w.error().kind, Error::Kind::Param);
}

// --- stages
// --------------------------------------------------------------------------------------------------------------

TEST(Smooth, MovesVerticesTowardsTheirWeightedRingMean) {
  io::TriangleMesh m = test::uv_sphere(1.0f, 64);
  std::mt19937 rng(2);
  std::uniform_real_distribution<float> u(-0.01f, 0.01f);
  for (auto& v : m.vertices) v += Vec3f(u(rng), u(rng), u(rng));
  // Spread of the radius about its mean: noise, not the (small, uniform) shrinkage of a Laplacian step.
  auto roughness = [](const io::TriangleMesh& mesh) {
    double mean = 0, s = 0;
    for (const auto& v : mesh.vertices) mean += v.norm();
    mean /= double(mesh.vertices.size());
    for (const auto& v : mesh.vertices) s += std::abs(v.norm() - mean);
    return s / double(mesh.vertices.size());
  };
  const double before = roughness(m);
  const io::TriangleMesh orig = m;
  smooth_weighted(m, {2, 0.5f, 0.3f});
  EXPECT_LT(roughness(m), 0.5 * before);
  EXPECT_EQ(m.triangles, orig.triangles);
  io::TriangleMesh same = orig;
  smooth_weighted(same, {2, 0.5f, 1e-4f});  // every neighbour beyond H_v: nothing moves
  for (std::size_t i = 0; i < same.vertices.size(); ++i) EXPECT_EQ(same.vertices[i], orig.vertices[i]);
}

TEST(SparseField, KeepsOnlyBlocksTheSurfacePassesThrough) {
  const Shape s = sphere_shape();
  auto f = sparse_field(s.particles, kD, SurfaceParams{});
  ASSERT_TRUE(f.has_value());
  EXPECT_GT(f->keys.size(), 0u);
  EXPECT_LT(f->keys.size(), f->candidate_blocks);
  EXPECT_TRUE(std::is_sorted(f->keys.begin(), f->keys.end()));
  // Deep inside a fluid at rest φ ≈ 1 (the lattice sum of the kernel).
  EXPECT_NEAR(f->max_value, 1.0f, 0.05f);
}

TEST(SparseField, AMemoryLimitBelowTheGridIsRefusedBeforeAnyBlockIsFilled) {
  const Shape s = sphere_shape();
  auto all = sparse_field(s.particles, kD, SurfaceParams{});
  ASSERT_TRUE(all.has_value());
  // The worst case (every candidate kept, 9³ floats and its bookkeeping each) just over and just under the limit.
  const double need_mib = double(all->candidate_blocks) * (4.0 * SparseField::kNodesPerBlock) / (1024.0 * 1024.0);
  auto refused = sparse_field(s.particles, kD, SurfaceParams{}, 0.9 * need_mib);
  ASSERT_FALSE(refused.has_value());
  EXPECT_EQ(refused.error().kind, Error::Kind::Param);
  const std::string& m = refused.error().message;
  EXPECT_NE(m.find(std::to_string(all->candidate_blocks) + " blocks"), std::string::npos) << m;
  EXPECT_NE(m.find("--max-memory"), std::string::npos) << m;
  EXPECT_NE(m.find("surface.cell_size"), std::string::npos) << m;
  EXPECT_TRUE(sparse_field(s.particles, kD, SurfaceParams{}, 1.2 * need_mib).has_value());
  // Through reconstruct, the same.
  EXPECT_FALSE(reconstruct(s.particles, kD, SurfaceParams{}, nullptr, 0.9 * need_mib).has_value());
}

}  // namespace
}  // namespace ff::surface
