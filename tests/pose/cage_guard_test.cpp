// The cage's guard (pose/cage_guard.h): the closest feature of a triangle is its closest point, and on a coarse bar
// bent through its clip the guarded cage keeps the samples inside the bent mesh where the cage alone lets some out,
// moves none at the bind pose but those nearer the surface than the least guard depth, and poses them smoothly.
#include "pose/cage_guard.h"
#include "pose/skin_eval.h"
#include "pose/mesh_anchors.h"
#include "sampling/mesh_field.h"
#include "support/skin_bar.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <random>
#include <utility>

namespace ff::pose {
namespace {

TEST(CageGuard, TheClosestFeatureIsTheTrianglesClosestPoint) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  int features[7] = {};
  for (int k = 0; k < 20000; ++k) {
    const Vec3f a(u(rng), u(rng), u(rng)), b(u(rng), u(rng), u(rng)), c(u(rng), u(rng), u(rng)),
        p(2 * u(rng), 2 * u(rng), 2 * u(rng));
    int f = -1;
    const Vec3f q = closest_feature(p, a, b, c, f);
    const Vec3f ref = sampling::closest_point_on_triangle(p, a, b, c);
    ASSERT_NEAR((p - q).norm(), (p - ref).norm(), 1e-4f) << k;
    ASSERT_TRUE(f >= 0 && f <= 6);
    ++features[f];
    // The feature named is where q lies: an edge's point is on that edge's line.
    if (f >= 1 && f <= 3) {
      const Vec3f s = f == 1 ? a : f == 2 ? b : c, e = (f == 1 ? b : f == 2 ? c : a) - s;
      EXPECT_LT((q - s).cross(e).norm(), 1e-4f * e.norm());
    }
  }
  for (int f = 0; f < 7; ++f) EXPECT_GT(features[f], 100) << "feature " << f;  // every region was reached
  // A triangle that repeats a corner (a needle of two points) or is one point: a finite point at the right distance.
  for (int k = 0; k < 2000; ++k) {
    const Vec3f a(u(rng), u(rng), u(rng)), b(u(rng), u(rng), u(rng)), p(2 * u(rng), 2 * u(rng), 2 * u(rng));
    for (const auto& [x, y, z] : {std::array<Vec3f, 3>{a, a, b}, std::array<Vec3f, 3>{a, b, a}, std::array<Vec3f, 3>{b, a, a},
                                  std::array<Vec3f, 3>{a, a, a}}) {
      int f = -1;
      const Vec3f q = closest_feature(p, x, y, z, f);
      ASSERT_TRUE(q.allFinite()) << k;
      // Its closest point is its edges' (as segments), worked out here: sampling::closest_point_on_triangle is no
      // reference there (on a triangle that repeats a corner it can return a farther point).
      float ref = std::numeric_limits<float>::infinity();
      for (const auto& [s0, s1] : {std::pair{x, y}, std::pair{y, z}, std::pair{z, x}}) {
        const Vec3f d = s1 - s0;
        const float t = d.squaredNorm() > 0.0f ? std::clamp((p - s0).dot(d) / d.squaredNorm(), 0.0f, 1.0f) : 0.0f;
        ref = std::min(ref, (p - (s0 + t * d)).norm());
      }
      EXPECT_NEAR((p - q).norm(), ref, 1e-4f) << k;
    }
  }
}

// Samples of the coarse bar (4 rings of 12), bent through its clip (0° → 90° over 1 s).
struct Bent {
  io::TriangleMesh bar = test::bar_mesh(4, 12);
  io::Skin skin = test::bar_skin(bar);
  std::vector<Vec3f> samples;
  float spacing = 0.02f;
};

PosedJoints bend(const io::Skin& skin, double t) {
  std::vector<io::Mat4f> K;
  pose::joint_matrices(skin, 0, t, K);
  PosedJoints j;
  j.set(std::move(K), SkinningMethod::Linear);
  return j;
}

TEST(CageGuard, TheGuardedCageKeepsTheBentBarsSamplesInside) {
  Bent s;
  auto field = sampling::MeshField::build(s.bar);
  ASSERT_TRUE(field.has_value());
  // A lattice of samples inside the bar at the spacing, up to its surface.
  for (float x = -0.1f; x <= 0.2f; x += s.spacing)
    for (float y = 0.01f; y < 1.0f; y += s.spacing)
      for (float z = -0.1f; z <= 0.1f; z += s.spacing)
        if (field->inside(Vec3f(x, y, z))) s.samples.emplace_back(x, y, z);
  auto cage = anchor_to_cage(s.bar, s.skin.joints, s.skin.weights, s.samples, std::size_t{1} << 26);
  ASSERT_TRUE(cage.has_value()) << cage.error().message;
  MeshAnchors guarded = *cage;
  std::vector<std::vector<Vec3f>> poses;
  for (int k = 0; k < kGuardPoses; ++k) guarded.pose_vertices(bend(s.skin, double(k) / (kGuardPoses - 1)), poses.emplace_back());
  auto stats = guard_cage(guarded, *field, poses, s.spacing);
  ASSERT_TRUE(stats.has_value()) << stats.error().message;
  ASSERT_TRUE(guarded.consistent(s.samples.size()));
  std::printf("bar: %zu samples, %zu guarded (%.1f triangles each)\n", s.samples.size(), stats->guarded,
              double(stats->triangles) / double(stats->guarded));
  EXPECT_GT(stats->guarded, 0u);
  EXPECT_LT(stats->guarded, s.samples.size());
  // At the bind pose only samples nearer the surface than the least guard depth move, and only inward, by less than it.
  for (std::size_t i = 0; i < s.samples.size(); ++i) {
    const Vec3f x = guarded.place(i, s.bar.vertices);
    const float depth = -field->signed_distance(s.samples[i]);
    if (depth >= kMinGuardDepth * s.spacing) {
      EXPECT_LT((x - s.samples[i]).norm(), 1e-5f) << i;
    } else {
      EXPECT_LT((x - s.samples[i]).norm(), kMinGuardDepth * s.spacing) << i;
      EXPECT_GE(-field->signed_distance(x), depth - 1e-6f) << i;
    }
  }
  // Bent: the share inside the bent mesh, the cage alone against the guarded cage; and the guarded samples move
  // smoothly (no step between two close times larger than the cage's own motion allows).
  std::size_t out_cage = 0, out_guarded = 0;
  for (const double t : {0.25, 0.5, 0.75, 1.0}) {
    std::vector<Vec3f> p;
    cage->pose_vertices(bend(s.skin, t), p);
    io::TriangleMesh bent = s.bar;
    bent.vertices = p;
    auto bent_field = sampling::MeshField::build(bent);
    ASSERT_TRUE(bent_field.has_value());
    std::size_t in_cage = 0, in_guarded = 0;
    for (std::size_t i = 0; i < s.samples.size(); ++i) {
      in_cage += bent_field->inside(cage->place(i, p));
      in_guarded += bent_field->inside(guarded.place(i, p));
    }
    std::printf("bar bent at t = %.2f: %zu of %zu samples outside by the cage alone, %zu guarded\n", t,
                s.samples.size() - in_cage, s.samples.size(), s.samples.size() - in_guarded);
    out_cage += s.samples.size() - in_cage, out_guarded += s.samples.size() - in_guarded;
  }
  EXPECT_GT(out_cage, 0u);  // the case needs a guard: the cage alone lets samples out at the sharpest bend (5 of 3700)
  EXPECT_EQ(out_guarded, 0u);
  std::vector<Vec3f> p0, p1;
  guarded.pose_vertices(bend(s.skin, 0.5), p0);
  guarded.pose_vertices(bend(s.skin, 0.5 + 1e-3), p1);
  float step_cage = 0.0f, step_guarded = 0.0f;
  for (std::size_t i = 0; i < s.samples.size(); ++i) {
    step_cage = std::max(step_cage, (cage->place(i, p1) - cage->place(i, p0)).norm());
    step_guarded = std::max(step_guarded, (guarded.place(i, p1) - guarded.place(i, p0)).norm());
  }
  std::printf("largest step over 1 ms of the bend: cage %.2e m, guarded %.2e m\n", step_cage, step_guarded);
  EXPECT_LT(step_guarded, 3.0f * step_cage);
}

// The bar's field and a cage of one sample in it, for the tests that need only the mesh.
struct OneSample {
  Bent s;
  Result<sampling::MeshField> field = sampling::MeshField::build(s.bar);
  Result<MeshAnchors> cage = anchor_to_cage(s.bar, s.skin.joints, s.skin.weights, {Vec3f(0.05f, 0.5f, 0.0f)}, 1000);
};

// The exact winding number that a fold's samples are checked by, against the field's (in double) on the bent bar.
TEST(CageGuard, ThePosedWindingNumberIsTheFieldsOnTheBentBar) {
  OneSample one;
  ASSERT_TRUE(one.field.has_value() && one.cage.has_value());
  const Bent& s = one.s;
  auto& field = one.field;
  auto& cage = one.cage;
  std::vector<std::vector<Vec3f>> poses(1);
  cage->pose_vertices(bend(s.skin, 1.0), poses[0]);
  ASSERT_TRUE(guard_cage(*cage, *field, poses, s.spacing).has_value());
  io::TriangleMesh bent = s.bar;
  bent.vertices = poses[0];
  auto bent_field = sampling::MeshField::build(bent);
  ASSERT_TRUE(bent_field.has_value());
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(-0.3f, 1.2f);
  int inside = 0;
  for (int k = 0; k < 2000; ++k) {
    const Vec3f p(u(rng), u(rng), 0.3f * u(rng));
    const double ref = bent_field->winding_number_exact(p);
    const float w = posed_winding_number(*cage, poses[0], p);
    EXPECT_NEAR(w, ref, 1e-3) << k;
    inside += w > 0.5f;
  }
  EXPECT_GT(inside, 20);  // some of the points were inside
}

TEST(CageGuard, RefusesWhatDoesNotMatch) {
  OneSample one;
  ASSERT_TRUE(one.field.has_value() && one.cage.has_value());
  const Bent& s = one.s;
  auto& field = one.field;
  auto& cage = one.cage;
  std::vector<std::vector<Vec3f>> wrong{std::vector<Vec3f>(3, Vec3f::Zero())};
  EXPECT_FALSE(guard_cage(*cage, *field, wrong, s.spacing).has_value());
  EXPECT_FALSE(guard_cage(*cage, *field, {}, 0.0f).has_value());
  MeshAnchors sheet;
  EXPECT_FALSE(guard_cage(sheet, *field, {}, s.spacing).has_value());
  // A fold partner out of range, or one with a partner of its own, is not consistent.
  ASSERT_TRUE(guard_cage(*cage, *field, {}, s.spacing).has_value());
  ASSERT_TRUE(cage->consistent(1));
  cage->fold_partner = {5};
  EXPECT_FALSE(cage->consistent(1));
  cage->fold_partner = {0};
  EXPECT_FALSE(cage->consistent(1));
  cage->fold_partner = {kInvalidIndex};
  EXPECT_TRUE(cage->consistent(1));
}

}  // namespace
}  // namespace ff::pose
