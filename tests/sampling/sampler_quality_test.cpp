// Blue-noise volume sampling quality on a family of meshes, at a few
// thousand samples each: minimum pairwise distance ≥ 0.85 d, no point of the volume farther than
// 0.9 d from a sample (dense probes), count within ±5 % of V/d³ (V by Monte Carlo with the winding
// number, independent of the sampler's own estimate), every sample inside (signed distance ≤ 0.25 d).
#include "core/neighbor_grid.h"
#include "sampling/mesh_field.h"
#include "sampling/samplers.h"
#include "support/shapes.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>

namespace ff::sampling {
namespace {

struct Case {
  std::string name;
  io::TriangleMesh mesh;
  std::size_t samples;  // about this many (sets d)
};

// Uniform points in the box that are inside the mesh (winding number), and the inside fraction of the box.
std::vector<Vec3f> inside_probes(const MeshField& f, std::size_t want, double& volume) {
  const Aabb b = f.bounds();
  std::mt19937 rng(42);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::vector<Vec3f> in;
  std::size_t tried = 0;
  while (in.size() < want) {
    std::vector<Vec3f> p(65536);
    for (auto& x : p) x = b.min + Vec3f(u(rng), u(rng), u(rng)).cwiseProduct(b.size());
    std::vector<std::uint8_t> inside(p.size());
    f.inside(p, inside);
    for (std::size_t i = 0; i < p.size(); ++i)
      if (inside[i]) in.push_back(p[i]);
    tried += p.size();
  }
  const Vec3f s = b.size();
  volume = double(in.size()) / double(tried) * double(s.x()) * s.y() * s.z();
  return in;
}

void check(const Case& c) {
  SCOPED_TRACE(c.name);
  auto field = MeshField::build(c.mesh);
  ASSERT_TRUE(field.has_value()) << field.error().message;
  double volume = 0.0;
  const auto probes = inside_probes(*field, 200'000, volume);
  const float d = static_cast<float>(std::cbrt(volume / double(c.samples)));
  SamplingParams p;
  p.spacing = d;
  if (const char* seed = std::getenv("FF_SEED")) p.seed = std::strtoull(seed, nullptr, 10);
  SampleReport rep;
  auto set = sample_target(c.mesh, p, 0, &rep);
  ASSERT_TRUE(set.has_value()) << set.error().message;
  const auto& x = set->position;
  const double expect = volume / (double(d) * d * d);
  EXPECT_NEAR(double(x.size()), expect, 0.05 * expect) << "count";

  // Minimum distance: no pair closer than 0.85 d.
  core::NeighborGrid close(0.85f * d);
  close.build(x);
  core::NeighborList nl;
  close.neighbors(x, nl);
  EXPECT_EQ(nl.total(), 0u) << "pairs closer than 0.85 d";
  if (std::getenv("FF_DEBUG"))
    for (std::size_t i = 0; i < x.size(); ++i)
      for (Index j : nl.of(i))
        std::printf("close %.3f d at (%.3f %.3f %.3f) depth %.3f / %.3f d\n", (x[i] - x[j]).norm() / d, x[i].x(), x[i].y(), x[i].z(), -field->signed_distance(x[i]) / d, -field->signed_distance(x[j]) / d);
  std::printf("%s: d = %.4f, %zu samples (%zu dropped, %zu added by enforce_spacing) in %.2f s\n", c.name.c_str(), d,
              x.size(), rep.repaired_dropped, rep.repaired_added, rep.seconds);

  // Coverage: every probe has a sample within 0.9 d.
  core::NeighborGrid cover(0.9f * d);
  cover.build(x);
  cover.query(x, probes, 0.9f * d, nl);
  std::size_t uncovered = 0;
  for (std::size_t i = 0; i < probes.size(); ++i) {
    if (nl.of(i).empty() && uncovered < 5 && std::getenv("FF_DEBUG"))
      std::printf("uncovered (%.3f %.3f %.3f) depth %.3f d\n", probes[i].x(), probes[i].y(), probes[i].z(), -field->signed_distance(probes[i]) / d);
    uncovered += nl.of(i).empty() ? 1 : 0;
  }
  EXPECT_EQ(uncovered, 0u) << "probes farther than 0.9 d from every sample, of " << probes.size();

  // Inside: signed distance ≤ 0.25 d.
  std::vector<float> sd(x.size());
  field->signed_distance(x, sd);
  float worst = -1e30f;
  for (std::size_t i = 0; i < sd.size(); ++i) {
    if (sd[i] > 0.25f * d && std::getenv("FF_DEBUG"))
      std::printf("outside %.3f d at (%.3f %.3f %.3f) winding %.3f\n", sd[i] / d, x[i].x(), x[i].y(), x[i].z(),
                  field->winding_number(x[i]));
    worst = std::max(worst, sd[i]);
  }
  EXPECT_LE(worst, 0.25f * d) << "a sample is outside";

  // Weights on a real set: ω in (0, 1], φ̃ in [c, 1 + c] reaching both ends.
  const auto [wlo, whi] = std::minmax_element(set->weight.begin(), set->weight.end());
  EXPECT_GT(*wlo, 0.0f);
  EXPECT_LE(*whi, 1.0f);
  const auto [plo, phi] = std::minmax_element(set->phi.begin(), set->phi.end());
  EXPECT_NEAR(*plo, p.phi_offset, 1e-5f);
  EXPECT_NEAR(*phi, 1.0f + p.phi_offset, 1e-5f);
}

TEST(SamplerQuality, Sphere) { check({"sphere", test::uv_sphere(0.5f, 64), 4000}); }
TEST(SamplerQuality, Box) { check({"box", test::box(Vec3f(0.5f, 0.3f, 0.4f)), 4000}); }
TEST(SamplerQuality, Torus) { check({"torus", test::torus(0.5f, 0.2f, 64, 32), 4000}); }
TEST(SamplerQuality, ThinWalledVase) { check({"vase", test::vase(), 6000}); }
TEST(SamplerQuality, SphereWithAHole) { check({"sphere with a hole", test::sphere_with_hole(6), 4000}); }
TEST(SamplerQuality, TwoOverlappingParts) { check({"two overlapping spheres", test::two_overlapping_spheres(), 4000}); }
TEST(SamplerQuality, StanfordBunny) {
  auto bunny = test::stanford_bunny();
  ASSERT_TRUE(bunny.has_value()) << bunny.error().message;
  check({"bunny", *bunny, 5000});
}

}  // namespace
}  // namespace ff::sampling
