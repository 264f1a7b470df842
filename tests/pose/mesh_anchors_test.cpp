// Samples anchored to the posed mesh (pose/mesh_anchors.h). An open sheet's ride their posed triangles: at the bind
// pose every sample is placed where it was; posed, it lies on the posed sheet, where skinning it by its interpolated
// weights would leave it; and control::ControlSamples poses anchored samples so, with their velocity the placement's forward
// difference. A closed mesh's sit in it as a cage (mean value coordinates): reproduced exactly at bind, and inside the
// bent mesh. The skeleton is the hand-built bar of tests/support/skin_bar.h, its sheet a coarse strip.
#include "control/control_samples.h"
#include "pose/skin_eval.h"
#include "pose/mesh_anchors.h"
#include "sampling/mesh_field.h"
#include "support/skin_bar.h"

#include <gtest/gtest.h>

#include <limits>
#include <random>

namespace ff::pose {
namespace {

// A flat strip in the z = 0 plane, x ∈ [0, 0.1], y ∈ [0, 1], in `rings` rows of two triangles: an open sheet whose
// only vertices across the bend (y 0.4–0.6) are at ring heights, so its posed bend is cut at the corners.
io::TriangleMesh strip(int rings) {
  io::TriangleMesh m;
  for (int k = 0; k <= rings; ++k) {
    const float y = float(k) / float(rings);
    m.vertices.push_back(Vec3f(0.0f, y, 0.0f));
    m.vertices.push_back(Vec3f(0.1f, y, 0.0f));
  }
  for (int k = 0; k < rings; ++k) {
    const auto a = static_cast<Index>(2 * k);
    m.triangles.push_back({a, a + 1, a + 3});
    m.triangles.push_back({a, a + 3, a + 2});
  }
  return m;
}

struct Sheet {
  io::Skin skin;
  io::TriangleMesh mesh;
  std::vector<Vec3f> samples;  // on the strip, bind pose
  std::vector<std::array<float, 3>> bary;
  std::vector<Index> triangle;
};

Sheet make_sheet(int rings, std::size_t n, float max_height) {
  Sheet s;
  s.mesh = strip(rings);
  s.skin = test::bar_skin(s.mesh);
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(0.0f, 1.0f), h(-max_height, max_height);
  for (std::size_t i = 0; i < n; ++i) {
    const auto t = static_cast<Index>(rng() % s.mesh.triangles.size());
    float a = u(rng), b = u(rng);
    if (a + b > 1.0f) a = 1.0f - a, b = 1.0f - b;
    const auto& tri = s.mesh.triangles[t];
    const Vec3f x = (1 - a - b) * s.mesh.vertices[tri[0]] + a * s.mesh.vertices[tri[1]] + b * s.mesh.vertices[tri[2]];
    s.samples.push_back(x + Vec3f(0.0f, 0.0f, h(rng)));
    s.triangle.push_back(t);
  }
  return s;
}

Result<MeshAnchors> anchors_of(const Sheet& s) {
  return anchor_to_triangles(s.mesh, s.skin.joints, s.skin.weights, s.samples, [&](std::size_t i) { return s.triangle[i]; });
}

PosedJoints bend_at(const io::Skin& skin, double t) {
  std::vector<io::Mat4f> K;
  pose::joint_matrices(skin, 0, t, K);  // clip 0: "bend", mid turning 0° → 90° about z over 1 s
  PosedJoints j;
  j.set(std::move(K), SkinningMethod::Linear);
  return j;
}

// Distance from x to the nearest triangle of `mesh` with vertices `v`.
float sheet_distance(const io::TriangleMesh& mesh, const std::vector<Vec3f>& v, const Vec3f& x) {
  float best = std::numeric_limits<float>::infinity();
  for (const auto& t : mesh.triangles)
    best = std::min(best, (x - sampling::closest_point_on_triangle(x, v[t[0]], v[t[1]], v[t[2]])).norm());
  return best;
}

TEST(MeshAnchors, AtTheBindPoseEverySampleIsPlacedWhereItWas) {
  const Sheet s = make_sheet(5, 500, 0.02f);
  auto a = anchors_of(s);
  ASSERT_TRUE(a.has_value()) << a.error().message;
  float worst = 0.0f;
  for (std::size_t i = 0; i < s.samples.size(); ++i) worst = std::max(worst, (a->place(i, s.mesh.vertices) - s.samples[i]).norm());
  EXPECT_LT(worst, 1e-6f);
  // A degenerate triangle (its corners on one line) anchors a sample to its nearest corner, with no height.
  std::array<float, 3> bary;
  float height = 1.0f;
  triangle_anchor(Vec3f(0.9f, 0.1f, 0.0f), Vec3f::Zero(), Vec3f(0.5f, 0.0f, 0.0f), Vec3f(1.0f, 0.0f, 0.0f), bary, height);
  EXPECT_EQ(bary, (std::array<float, 3>{0.0f, 0.0f, 1.0f}));
  EXPECT_EQ(height, 0.0f);
}

TEST(MeshAnchors, PosedSamplesLieOnThePosedSheetWhereTheirOwnWeightsWouldLeaveIt) {
  const Sheet s = make_sheet(3, 400, 0.0f);
  auto a = anchors_of(s);
  ASSERT_TRUE(a.has_value()) << a.error().message;
  const PosedJoints joints = bend_at(s.skin, 1.0);  // bent 90°
  std::vector<Vec3f> posed;
  a->pose_vertices(joints, posed);
  float anchored = 0.0f, weighted = 0.0f;
  for (std::size_t i = 0; i < s.samples.size(); ++i) {
    anchored = std::max(anchored, sheet_distance(s.mesh, posed, a->place(i, posed)));
    // The sample skinned by its own weights: the vertices' weights interpolated at its barycentrics.
    const auto& tri = s.mesh.triangles[a->triangle[i]];
    io::Mat4f m = io::Mat4f::Zero();
    for (int k = 0; k < 3; ++k)
      m += a->bary[i][k] * io::blend_matrix(joints.matrices(), s.skin.joints[tri[k]], s.skin.weights[tri[k]]);
    const Vec3f x = m.topLeftCorner<3, 3>() * s.samples[i] + m.topRightCorner<3, 1>();
    weighted = std::max(weighted, sheet_distance(s.mesh, posed, x));
  }
  std::printf("bent strip: anchored samples within %.2g m of the posed sheet, weight-skinned ones %.3f m\n", anchored,
              weighted);
  EXPECT_LT(anchored, 1e-5f);
  EXPECT_GT(weighted, 0.01f);  // what the anchors are for: a coarse sheet's bend leaves weight-skinned samples off it
}

TEST(MeshAnchors, ControlSamplesPoseAnchoredSamplesAndTheirVelocity) {
  const Sheet s = make_sheet(4, 300, 0.01f);
  auto a = anchors_of(s);
  ASSERT_TRUE(a.has_value()) << a.error().message;
  control::ControlTarget ct;
  ct.set.position = s.samples;
  ct.set.velocity.assign(s.samples.size(), Vec3f::Zero());
  ct.set.density.assign(s.samples.size(), 1000.0f);
  ct.set.weight.assign(s.samples.size(), 1.0f);
  ct.set.phi.assign(s.samples.size(), 1.0f);
  ct.set.spacing = 0.02f, ct.set.support = 0.04f, ct.set.mass = 0.008f;
  auto skin = std::make_shared<TargetSkin>();
  skin->skin = s.skin;
  skin->clip = 0;
  skin->spec.clip = "bend";
  skin->spec.loop = false;
  ct.skin = skin;
  ct.skin_joints.resize(s.samples.size());
  ct.skin_weights.resize(s.samples.size());
  for (std::size_t i = 0; i < s.samples.size(); ++i) test::bar_influence(s.samples[i].y(), ct.skin_joints[i], ct.skin_weights[i]);
  ct.anchors = std::make_shared<const MeshAnchors>(*a);
  std::vector<control::ControlTarget> targets;
  targets.push_back(ct);
  control::ControlSamples cs;
  ASSERT_TRUE(cs.init(targets, "test", control::SampleOptions{.cell_order = true, .velocities = true}).ok());
  const double t = 0.6;
  const float dt = 0.01f;
  cs.update(t, dt);
  std::vector<Vec3f> now, next;
  a->pose_vertices(bend_at(s.skin, t), now);
  a->pose_vertices(bend_at(s.skin, t + dt), next);
  float worst_x = 0.0f, worst_v = 0.0f, speed = 0.0f;
  for (std::size_t k = 0; k < cs.size(); ++k) {
    const std::size_t i = cs.original[k];  // cell order permutes the samples
    const Vec3f x = a->place(i, now), v = (a->place(i, next) - x) / dt;
    worst_x = std::max(worst_x, (cs.position[k] - x).norm());
    worst_v = std::max(worst_v, (cs.velocity[k] - v).norm());
    speed = std::max(speed, v.norm());
  }
  EXPECT_LT(worst_x, 1e-6f);
  EXPECT_LT(worst_v, 1e-3f * speed);
  EXPECT_GT(speed, 0.1f);  // the bend moves the samples
  // Anchors that do not match the samples are refused, naming the target.
  auto short_anchors = std::make_shared<MeshAnchors>(*a);
  short_anchors->triangle.pop_back();
  targets[0].anchors = short_anchors;
  const Status refused = control::ControlSamples{}.init(targets, "test", control::SampleOptions{});
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.error().message.find("targets[0]: mesh anchors that do not match"), std::string::npos) << refused.error().message;
}

TEST(MeshAnchors, ACageReproducesItsSamplesAndKeepsThemInsideTheBentMesh) {
  // The bar, coarse (3 rings of 6): bent 90° at its middle, its posed surface cuts the bend's corner.
  const io::TriangleMesh bar = test::bar_mesh(3, 6);
  const io::Skin skin = test::bar_skin(bar);
  auto field = sampling::MeshField::build(bar);
  ASSERT_TRUE(field.has_value());
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f), y(0.0f, 1.0f);
  std::vector<Vec3f> samples;
  while (samples.size() < 2000) {
    const Vec3f x(test::kBarX + test::kBarRadius * u(rng), test::kBarHeight * y(rng), test::kBarRadius * u(rng));
    if (field->signed_distance(x) < -0.005f) samples.push_back(x);
  }
  auto cage = anchor_to_cage(bar, skin.joints, skin.weights, samples, std::size_t{1} << 24);
  ASSERT_TRUE(cage.has_value()) << cage.error().message;
  ASSERT_TRUE(cage->caged());
  float worst = 0.0f, worst_sum = 0.0f;
  for (std::size_t i = 0; i < samples.size(); ++i) {
    worst = std::max(worst, (cage->place(i, bar.vertices) - samples[i]).norm());
    float sum = 0.0f;
    for (std::size_t v = 0; v < bar.vertices.size(); ++v) sum += cage->cage[i * bar.vertices.size() + v];
    worst_sum = std::max(worst_sum, std::abs(sum - 1.0f));
  }
  EXPECT_LT(worst, 1e-5f);
  EXPECT_LT(worst_sum, 1e-5f);
  const PosedJoints joints = bend_at(skin, 1.0);
  std::vector<Vec3f> posed;
  cage->pose_vertices(joints, posed);
  io::TriangleMesh bent = bar;
  bent.vertices = posed;
  auto bent_field = sampling::MeshField::build(bent);
  ASSERT_TRUE(bent_field.has_value());
  std::size_t caged_in = 0, weighted_in = 0;
  for (std::size_t i = 0; i < samples.size(); ++i) {
    caged_in += bent_field->inside(cage->place(i, posed));
    std::array<std::uint16_t, io::kMaxInfluences> j;
    std::array<float, io::kMaxInfluences> w;
    test::bar_influence(samples[i].y(), j, w);
    weighted_in += bent_field->inside(joints.apply(j, w, samples[i]));
  }
  const double caged = double(caged_in) / double(samples.size()), weighted = double(weighted_in) / double(samples.size());
  std::printf("bent coarse bar: %.2f %% of caged samples inside, %.2f %% of weight-skinned ones\n", 100 * caged, 100 * weighted);
  EXPECT_GE(caged, 0.99);
  EXPECT_GT(caged, weighted);
  // Weights that would exceed the limit are refused before they are allocated, naming the knob.
  auto big = anchor_to_cage(bar, skin.joints, skin.weights, samples, 1000);
  ASSERT_FALSE(big.has_value());
  EXPECT_NE(big.error().message.find("\"follow\": \"weights\""), std::string::npos) << big.error().message;
}

}  // namespace
}  // namespace ff::pose
