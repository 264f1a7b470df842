// Skinned, animated targets (issue 19): a file's skin read through Assimp, its control samples weighted and posed,
// on the demo character and assimp-testmodels' skinned files.
#include "io/load_mesh.h"
#include "pose/skin_eval.h"
#include "io/skin.h"
#include "pipeline/auto_scene.h"
#include "pipeline/scene_setup.h"
#include "pipeline/skinned_setup.h"
#include "sampling/mesh_field.h"
#include "support/test_support.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <ostream>
#include <random>

namespace ff::pipeline {
namespace {
namespace fs = std::filesystem;

struct SkinnedCase {
  std::string name;
  fs::path mesh;
  std::string clip;
  Vec3f scale;
  /// A sheet's samples stay within this many d_c of the posed sheet: they ride its posed triangles
  /// (pose::MeshAnchors; measured 0.0000 d_c on simple_skin.gltf. Skinned by their own weights they were
  /// 1.03 d_c off, where the 10-vertex sheet cuts its bend's corner).
  float sheet_tolerance = 0.01f;
};

// A stable ctest name: printed as its name, not as raw bytes (why: PrintTo in tests/e2e/character_test.cpp).
void PrintTo(const SkinnedCase& c, std::ostream* os) { *os << c.name; }

fs::path character_glb() {
  static const fs::path file = [] {
    const fs::path out = test::temp_dir("character") / "character.glb";
    const std::string cmd = fmt::format("/usr/bin/python3 {}/scripts/make_character.py --out {} > /dev/null",
                                        test::source_dir().string(), out.string());
    return std::system(cmd.c_str()) == 0 ? out : fs::path();
  }();
  return file;
}

std::vector<SkinnedCase> cases() {
  return {{"character", character_glb(), "walk", Vec3f::Ones()},
          {"simple_skin", "/usr/share/assimp/models/glTF2/simple_skin/simple_skin.gltf", "0", Vec3f::Ones()},
          {"anim_test", "/usr/share/assimp/models/X/anim_test.x", "0", Vec3f::Constant(0.1f)},
          {"huesitos", "/usr/share/assimp/models/FBX/huesitos.fbx", "0", Vec3f::Constant(0.01f)}};
}

class Skinned : public ::testing::TestWithParam<SkinnedCase> {};

TEST_P(Skinned, PosedSamplesLieInsideThePosedMeshThroughTheClip) {
  const SkinnedCase& c = GetParam();
  // scripts/setup installs python3-numpy (the generator's) and assimp-testmodels: a missing file is a failure.
  ASSERT_FALSE(c.mesh.empty()) << "scripts/make_character.py failed";
  ASSERT_TRUE(fs::exists(c.mesh)) << c.mesh;
  scene::Scene scene;
  scene::TargetSpec t;
  t.mesh = c.mesh;
  t.transform.scale = c.scale;
  t.animation.clip = c.clip;
  if (std::getenv("FF_W")) t.animation.weights = pose::SkinWeightSource::ClosestPoint;
  scene.targets.push_back(t);
  scene.auto_radius = true;
  if (c.name == "simple_skin") {  // a sheet: its own fluid box and spacing, which its sheet tolerance was measured at
    sim::FluidSource box;
    box.max = Vec3f(1.0f, 1.0f, 1.0f);
    scene.fluid.push_back(box);
    scene.auto_radius = false;
    scene.solver.particle_radius = 0.02f;
  }
  scene.sampling.auto_count = 4000;
  auto geometry = load_target_meshes(scene);
  ASSERT_TRUE(geometry.has_value()) << geometry.error().message;
  ASSERT_TRUE((*geometry)[0].skin) << "no skin";
  const Status completed = complete_scene(scene, *geometry);
  ASSERT_TRUE(completed.ok()) << completed.error().message;
  auto setup = setup_targets(scene, *geometry, test::temp_dir("skinned-cache-" + c.name), test::temp_dir("skinned-rep"),
                             core::null_progress());
  ASSERT_TRUE(setup.has_value()) << setup.error().message;
  const auto& sk = *setup->shapes[0].skinned;
  const double duration = sk.skin->skin.clips[static_cast<std::size_t>(sk.skin->clip)].duration;
  ASSERT_GT(duration, 0.0);
  auto bind_field = sampling::MeshField::build(sk.bind_mesh);
  ASSERT_TRUE(bind_field.has_value());
  const bool sheet = !bind_field->encloses_volume();
  // How the samples follow (SampleFollow::Auto): anchored to the posed mesh for the sheet and for huesitos' 62-vertex
  // cage (4017 samples, 65 per vertex); skinned by their own weights for the finer meshes.
  EXPECT_EQ(sk.anchors != nullptr, c.name == "simple_skin" || c.name == "huesitos") << c.name;
  if (sk.anchors) {
    EXPECT_EQ(sk.anchors->caged(), !sheet) << c.name;
  }
  // How far the clip ends from where it starts, and so whether it loops back and forth (ClipWrap::Auto): huesitos'
  // and anim_test's clips end 79 % and 16 % of their size away; the walk and simple_skin's bend cycle.
  const double seam = clip_seam(*sk.skin, sk.bind_mesh);
  std::printf("%s: the clip ends %.4f of the mesh's size from where it starts\n", c.name.c_str(), seam);
  if (c.name == "huesitos") {
    EXPECT_NEAR(seam, 0.786, 0.01);
  } else if (c.name == "anim_test") {
    EXPECT_NEAR(seam, 0.165, 0.01);
  } else {
    EXPECT_LT(seam, 1e-4) << c.name;
  }
  EXPECT_EQ(sk.skin->pingpong, c.name == "huesitos" || c.name == "anim_test") << c.name;
  // The share of its bind volume the posed mesh keeps at worst, which an automatic fluid is sized to.
  const double share = posed_volume_share(*sk.skin, sk.bind_mesh);
  std::printf("%s: the posed mesh keeps %.1f %% of its bind volume at worst\n", c.name.c_str(), 100.0 * share);
  if (c.name == "huesitos") {
    EXPECT_NEAR(share, 0.88, 0.02);
  } else if (!sheet) {
    EXPECT_GT(share, 0.95) << c.name;
  }
  std::vector<std::uint8_t> in_bind(sk.bind_samples.size());
  std::size_t n_in = 0;
  for (std::size_t i = 0; i < in_bind.size(); ++i) n_in += in_bind[i] = bind_field->inside(sk.bind_samples[i]);
  std::printf("%s: %zu samples, %.2f %% inside the bind mesh%s\n", c.name.c_str(), in_bind.size(),
              100.0 * double(n_in) / double(in_bind.size()), sheet ? " (a sheet)" : "");
  if (sk.anchors && sk.anchors->caged()) {
    // A cage is guarded (pose/cage_guard.h); what the guard adds to placing the samples, one thread, 20 poses.
    ASSERT_TRUE(sk.anchors->guarded());
    pose::MeshAnchors bare = *sk.anchors;
    bare.guard_begin.clear();
    double guarded_s = 0.0, bare_s = 0.0;
    Vec3f sum = Vec3f::Zero();  // kept, so the placing is not optimised away
    for (int k = 0; k < 20; ++k) {
      std::vector<io::Mat4f> K;
      sk.skin->world_joint_matrices(duration * k / 20.0, K);
      pose::PosedJoints joints;
      joints.set(K, pose::SkinningMethod::Linear);
      std::vector<Vec3f> v;
      bare.pose_vertices(joints, v);
      for (const pose::MeshAnchors* a : std::initializer_list<const pose::MeshAnchors*>{sk.anchors.get(), &bare}) {
        const auto t0 = std::chrono::steady_clock::now();
        for (std::size_t i = 0; i < sk.bind_samples.size(); ++i) sum += a->place(i, v);
        (a == &bare ? bare_s : guarded_s) += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      }
    }
    std::printf("%s: placing %zu samples in the cage, %.3f ms alone, %.3f ms guarded (one thread)\n", c.name.c_str(),
                sk.bind_samples.size(), 1e3 * bare_s / 20, 1e3 * guarded_s / 20);
    EXPECT_TRUE(std::isfinite(sum.norm()));
  }
  for (int k = 0; k <= 4; ++k) {
    const double time = duration * k / 4.0 * 0.999;
    std::vector<io::Mat4f> K;
    sk.skin->world_joint_matrices(time, K);
    pose::PosedJoints joints;
    joints.set(K, pose::SkinningMethod::Linear);
    io::TriangleMesh posed = sk.bind_mesh;
    for (std::size_t v = 0; v < posed.vertices.size(); ++v)
      posed.vertices[v] = joints.apply(sk.mesh_joints[v], sk.mesh_weights[v], sk.bind_mesh.vertices[v]);
    auto field = sampling::MeshField::build(posed);
    ASSERT_TRUE(field.has_value());
    const std::vector<Vec3f> x = posed_samples(sk, time, pose::SkinningMethod::Linear);
    if (sheet) {
      // A sheet's samples lie on it: posed, they stay on the posed sheet.
      float worst = 0.0f;
      for (std::size_t i = 0; i < sk.bind_samples.size(); ++i)
        worst = std::max(worst, field->unsigned_distance(x[i]));
      std::printf("%s t=%.3f: posed samples within %.4f m (%.2f d_c) of the posed sheet\n", c.name.c_str(), time, worst,
                  worst / sk.spacing);
      EXPECT_LE(worst, c.sheet_tolerance * sk.spacing) << c.name << " at t = " << time;
      continue;
    }
    std::size_t kept = 0;
    for (std::size_t i = 0; i < sk.bind_samples.size(); ++i)
      if (in_bind[i]) kept += field->inside(x[i]);
    const double frac = double(kept) / double(n_in);
    if (sk.anchors && sk.anchors->caged()) {  // the cage without its guard, for the record
      pose::MeshAnchors bare = *sk.anchors;
      bare.guard_begin.clear();
      std::vector<Vec3f> v;
      bare.pose_vertices(joints, v);
      std::size_t bare_kept = 0, eased_kept = 0;
      for (std::size_t i = 0; i < sk.bind_samples.size(); ++i)
        if (in_bind[i]) {
          bare_kept += field->inside(bare.place(i, v));
          eased_kept += field->inside(sk.anchors->place(i, v, /*folds=*/false));
        }
      std::printf("%s t=%.3f: the cage alone keeps %.2f %% inside, eased in by its guard %.2f %%\n", c.name.c_str(), time,
                  100.0 * double(bare_kept) / double(n_in), 100.0 * double(eased_kept) / double(n_in));
      // The fold path: where huesitos folds (k = 1, 2), easing in alone leaves samples in the fold's pocket, and moving
      // them towards their partners brings more of them in; elsewhere it moves none out.
      if (c.name == "huesitos") {
        EXPECT_FALSE(sk.anchors->fold_partner.empty());
        if (k == 1 || k == 2) {
          EXPECT_LT(eased_kept, kept) << "at t = " << time;
        } else {
          EXPECT_GE(kept, eased_kept) << "at t = " << time;
        }
      }
    }
    // Triangles the pose turns inside out (linear blend skinning folds a coarse mesh's crushed bend over itself): just
    // outside one the winding number is no longer below ½, or just inside no longer above, where at bind it was. The
    // fold's pocket is outside by the winding number though inside by its nearest triangle, and no sample placed from
    // the mesh is sure to stay out of it (pose/cage_guard.h). (At bind, a triangle inside another part, as the demo
    // character's overlapping limbs have, is not a surface triangle and is not counted.)
    int folded = 0;
    for (const auto& tri : posed.triangles) {
      const auto surface = [&](const sampling::MeshField& f, const std::vector<Vec3f>& v, const Vec3f& out) {
        const Vec3f mid = (v[tri[0]] + v[tri[1]] + v[tri[2]]) / 3.0f, d = 0.05f * sk.spacing * out;
        return f.winding_number(mid + d) < 0.5f && f.winding_number(mid - d) > 0.5f;
      };
      const auto normal = [&](const std::vector<Vec3f>& v) {
        const Vec3f n = (v[tri[1]] - v[tri[0]]).cross(v[tri[2]] - v[tri[0]]);
        return n.norm() > 0.0f ? Vec3f(n.normalized()) : Vec3f::Zero();
      };
      const Vec3f nb = normal(sk.bind_mesh.vertices), np = normal(posed.vertices);
      if (nb.isZero() || np.isZero()) continue;
      // The file's winding may be inward: the side of the bind triangle that is outside decides (both ways tried).
      const float sign = surface(*bind_field, sk.bind_mesh.vertices, nb) ? 1.0f : -1.0f;
      if (!surface(*bind_field, sk.bind_mesh.vertices, sign * nb)) continue;
      folded += !surface(*field, posed.vertices, sign * np);
    }
    const Vec3f size = field->bounds().size();
    // The posed mesh's own volume against its bind volume: linear blend skinning of a coarse mesh caves in at the
    // bends (huesitos loses 9-12 % at two of these times), and samples that keep their volume cannot all fit inside.
    std::printf("%s t=%.3f: %.2f %% of the samples inside at bind are inside the posed mesh; its size %.3f %.3f %.3f, "
                "its volume %.1f %% of the bind mesh's; %d of its %zu surface triangles no longer bound it (folded, or in another part)\n",
                c.name.c_str(), time, 100.0 * frac, size.x(), size.y(), size.z(), 100.0 * field->volume() / bind_field->volume(),
                folded, posed.triangles.size());
    // ≥ 99 % at every time, as issue 19 asks. huesitos.fbx is a 62-vertex cylinder bent through 9 bones: its posed
    // surface is the linear interpolation of a few far-apart posed vertices, which cuts the corners of every bend; it
    // folds three triangles inside out at t = 0.39 s (winding −1 and −2 beside them) and three into the body at
    // 0.78 s. Skinned by their own weights its samples followed the smooth blend of the bones (86 % stayed inside);
    // held in the mesh as a cage (pose/mesh_anchors.h) 96.4 % did at worst; eased in by its guard
    // (pose/cage_guard.h) 97.8 % and 99.3 % where the mesh folds, 100 % elsewhere; with the folds' samples moved
    // to their partners, 100 % at all five times.
    EXPECT_GE(frac, 0.99) << c.name << " at t = " << time << ", " << folded << " triangles folded";
    // huesitos folds at these two times only; anim_test never.
    if (c.name == "huesitos" || c.name == "anim_test") {
      EXPECT_EQ(folded > 0, c.name == "huesitos" && (k == 1 || k == 2)) << c.name << " at t = " << time;
    }
  }
}

// The two ways to weight the samples (closest point, diffusion) and to pose them (linear blend, dual quaternion),
// measured on the walking character: the samples inside at bind that stay inside the posed mesh, and how much the
// posed samples' nearest-neighbour distances change (tearing apart or crushing together), worst time of the clip.
// Assimp reads the skin in a child process (io/isolate.h); what comes back through the pipe is the skin read here.
TEST_P(Skinned, TheSkinReadInAChildProcessIsTheSkinReadHere) {
  const SkinnedCase& c = GetParam();
  ASSERT_FALSE(c.mesh.empty()) << "scripts/make_character.py failed";
  io::LoadOptions o;
  o.transform.scale = c.scale;
  auto mesh = io::load_mesh(c.mesh, o);
  ASSERT_TRUE(mesh.has_value()) << mesh.error().message;
  auto a = io::load_skin(c.mesh, *mesh, o.transform, true);
  auto b = io::load_skin(c.mesh, *mesh, o.transform, false);
  ASSERT_TRUE(a.has_value()) << a.error().message;
  ASSERT_TRUE(b.has_value()) << b.error().message;
  ASSERT_TRUE(a->has_value() && b->has_value());
  const io::Skin& x = **a;
  const io::Skin& y = **b;
  ASSERT_EQ(x.nodes.size(), y.nodes.size());
  for (std::size_t i = 0; i < x.nodes.size(); ++i) {
    EXPECT_EQ(x.nodes[i].name, y.nodes[i].name);
    EXPECT_EQ(x.nodes[i].parent, y.nodes[i].parent);
    EXPECT_EQ(x.nodes[i].local(), y.nodes[i].local());
  }
  EXPECT_EQ(x.joint_nodes, y.joint_nodes);
  EXPECT_EQ(x.inverse_bind, y.inverse_bind);
  EXPECT_EQ(x.joints, y.joints);
  EXPECT_EQ(x.weights, y.weights);
  EXPECT_EQ(x.warnings, y.warnings);
  ASSERT_EQ(x.clips.size(), y.clips.size());
  for (std::size_t k = 0; k < x.clips.size(); ++k) {
    EXPECT_EQ(x.clips[k].name, y.clips[k].name);
    EXPECT_EQ(x.clips[k].duration, y.clips[k].duration);
    ASSERT_EQ(x.clips[k].channels.size(), y.clips[k].channels.size());
    for (std::size_t h = 0; h < x.clips[k].channels.size(); ++h) {
      const auto& p = x.clips[k].channels[h];
      const auto& q = y.clips[k].channels[h];
      EXPECT_EQ(p.node, q.node);
      EXPECT_EQ(p.translation_times, q.translation_times);
      EXPECT_EQ(p.rotation_times, q.rotation_times);
      EXPECT_EQ(p.scale_times, q.scale_times);
      EXPECT_EQ(p.translations, q.translations);
      EXPECT_EQ(p.scales, q.scales);
      ASSERT_EQ(p.rotations.size(), q.rotations.size());
      for (std::size_t r = 0; r < p.rotations.size(); ++r) EXPECT_EQ(p.rotations[r].coeffs(), q.rotations[r].coeffs());
    }
  }
  // Posed at a time inside the clip, the two skins put every vertex at the same place.
  std::vector<io::Mat4f> kx, ky;
  pose::joint_matrices(x, 0, 0.5 * x.clips[0].duration, kx);
  pose::joint_matrices(y, 0, 0.5 * y.clips[0].duration, ky);
  EXPECT_EQ(kx, ky);
  EXPECT_GT(x.clips[0].channels.size(), 0u);
}

TEST(SkinnedMethods, MeasuredOnTheWalkingCharacter) {
  const fs::path glb = character_glb();
  ASSERT_FALSE(glb.empty());
  std::printf("%-14s %-16s %12s %14s %14s %9s %9s\n", "weights", "skinning", "kept inside", "mean |dNN|/d", "p99 |dNN|/d",
              "rho p1", "rho p99");
  for (const auto weights : {pose::SkinWeightSource::ClosestPoint, pose::SkinWeightSource::Diffusion}) {
    scene::Scene scene;
    scene::TargetSpec t;
    t.mesh = glb;
    t.animation.clip = "walk";
    t.animation.weights = weights;
    scene.targets.push_back(t);
    scene.auto_radius = true;
    scene.sampling.auto_count = 4000;
    auto geometry = load_target_meshes(scene);
    ASSERT_TRUE(geometry.has_value());
    ASSERT_TRUE(complete_scene(scene, *geometry).ok());
    auto setup = setup_targets(scene, *geometry, test::temp_dir("methods-cache"), test::temp_dir("methods-rep"),
                               core::null_progress());
    ASSERT_TRUE(setup.has_value());
    const auto& sk = *setup->shapes[0].skinned;
    auto bind_field = sampling::MeshField::build(sk.bind_mesh);
    ASSERT_TRUE(bind_field.has_value());
    std::vector<float> nn_bind(sk.bind_samples.size());
    std::vector<Index> nn_of(sk.bind_samples.size());
    for (std::size_t i = 0; i < nn_bind.size(); ++i) {
      // The nearest other sample at bind (brute force: a few thousand samples).
      float best = INFINITY;
      Index who = kInvalidIndex;
      for (std::size_t j = 0; j < nn_bind.size(); ++j) {
        if (j == i) continue;
        const float d2 = (sk.bind_samples[j] - sk.bind_samples[i]).squaredNorm();
        if (d2 < best) best = d2, who = static_cast<Index>(j);
      }
      nn_bind[i] = std::sqrt(best), nn_of[i] = who;
    }
    // How the pose compresses or stretches the samples: each one's Poly6 kernel sum over the others within
    // H_c = 3 d_c, posed against bind (what ρ_c would become if it followed the pose). Brute force over all pairs (a
    // few thousand samples); the bind sums once, every pose divides by them.
    const float h = 3.0f * sk.spacing, h2 = h * h;
    const auto kernel_sum = [&](const std::vector<Vec3f>& pts, std::size_t i) {
      double sum = 0.0;
      for (std::size_t j = 0; j < pts.size(); ++j) {
        const float r2 = (pts[j] - pts[i]).squaredNorm();
        if (r2 < h2) {
          const double w = double(h2 - r2);
          sum += w * w * w;
        }
      }
      return sum;
    };
    std::vector<double> bind_sum(sk.bind_samples.size());
    for (std::size_t i = 0; i < bind_sum.size(); ++i) bind_sum[i] = kernel_sum(sk.bind_samples, i);
    for (const auto method : {pose::SkinningMethod::Linear, pose::SkinningMethod::DualQuaternion}) {
      double worst_kept = 1.0, worst_mean = 0.0, worst_p99 = 0.0, rho_p1 = 1.0, rho_p99 = 1.0;
      // Four poses through the clip; under a sanitizer two of them (halfway and the end).
      for (int k = test::kSanitized ? 2 : 1; k <= 4; k += test::kSanitized ? 2 : 1) {
        const double time = 1.1 * k / 4.0 * 0.999;
        std::vector<io::Mat4f> K;
        sk.skin->world_joint_matrices(time, K);
        pose::PosedJoints joints;
        joints.set(K, method);
        io::TriangleMesh posed = sk.bind_mesh;
        for (std::size_t v = 0; v < posed.vertices.size(); ++v)
          posed.vertices[v] = joints.apply(sk.mesh_joints[v], sk.mesh_weights[v], sk.bind_mesh.vertices[v]);
        auto field = sampling::MeshField::build(posed);
        ASSERT_TRUE(field.has_value());
        const std::vector<Vec3f> x = posed_samples(sk, time, method);
        std::size_t in = 0, kept = 0;
        std::vector<double> change(x.size());
        for (std::size_t i = 0; i < x.size(); ++i) {
          if (bind_field->inside(sk.bind_samples[i])) ++in, kept += field->inside(x[i]);
          change[i] = std::abs((x[i] - x[nn_of[i]]).norm() - nn_bind[i]) / sk.spacing;
        }
        double mean = 0.0;
        for (double c : change) mean += c;
        mean /= double(change.size());
        std::sort(change.begin(), change.end());
        std::vector<double> ratio(x.size());
        for (std::size_t i = 0; i < x.size(); ++i) ratio[i] = kernel_sum(x, i) / bind_sum[i];
        std::sort(ratio.begin(), ratio.end());
        rho_p1 = std::min(rho_p1, ratio[ratio.size() / 100]);
        rho_p99 = std::max(rho_p99, ratio[ratio.size() * 99 / 100]);
        worst_kept = std::min(worst_kept, double(kept) / double(in));
        worst_mean = std::max(worst_mean, mean);
        worst_p99 = std::max(worst_p99, change[change.size() * 99 / 100]);
      }
      std::printf("%-14s %-16s %11.2f%% %14.4f %14.4f %9.3f %9.3f\n",
                  weights == pose::SkinWeightSource::Diffusion ? "diffusion" : "closest_point",
                  method == pose::SkinningMethod::Linear ? "linear" : "dual_quaternion", 100.0 * worst_kept, worst_mean,
                  worst_p99, rho_p1, rho_p99);
      EXPECT_GE(worst_kept, 0.99);
    }
  }
}

// Every measured frame of a skinned target measures the fluid against its posed mesh's own field (posed_shape: the
// mesh's vertices skinned, closest triangle and winding number queried exactly) instead of rebuilding the posed
// mesh's SDF grid (posed_shape_rebuilt, ~2 s a frame at 9k samples). On the walking character at five times of the
// clip, with "fluid" spread around the posed samples (up to 2 d inside and out, and a few far splashes), both must give
// the same E (the same posed samples) and inside and splash shares within a percentage point, with the signed
// distance's tests (inside: ≤ r, splash: > 2r) agreeing for ≥ 99 % of the points (the grid interpolates at d/2).
TEST(SkinnedMetrics, ThePosedMeshFieldAgreesWithTheRebuiltPosedShape) {
  const fs::path glb = character_glb();
  ASSERT_FALSE(glb.empty()) << "scripts/make_character.py failed";
  auto setup = test::skinned_setup(glb, "walk", 1.0f, test::temp_dir("posed-metrics"));
  ASSERT_TRUE(setup.has_value()) << setup.error().message;
  const TargetShapes& shapes = setup->setup.shapes[0];
  const auto& sk = setup->skinned();
  const float r = setup->scene.solver.particle_radius, d = 2.0f * r;
  const pose::Pose pose = setup->setup.motions[0].at(0.0);
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-2.0f * d, 2.0f * d);
  double fast_s = 0, rebuilt_s = 0;
  // Five times through the clip; under a sanitizer three of them (the start, halfway and the end).
  const int times = test::kSanitized ? 3 : 5;
  for (int k = 0; k <= 4; k += 4 / (times - 1)) {
    const double time = 1.1 * k / 4.0 * 0.999;
    const auto t0 = std::chrono::steady_clock::now();
    auto rebuilt = posed_shape_rebuilt(sk, pose, time);
    const auto t1 = std::chrono::steady_clock::now();
    auto fast = posed_shape(shapes.shape[0], sk, pose, time);
    const auto t2 = std::chrono::steady_clock::now();
    ASSERT_TRUE(rebuilt.has_value()) << rebuilt.error().message;
    ASSERT_TRUE(fast.has_value()) << fast.error().message;
    rebuilt_s += std::chrono::duration<double>(t1 - t0).count();
    fast_s += std::chrono::duration<double>(t2 - t1).count();
    ASSERT_FLOAT_EQ(fast->diagonal(), rebuilt->diagonal());
    // The fluid: every posed sample moved by up to 2 d on each axis, and every 50th thrown 0.3 m away.
    std::vector<Vec3f> x;
    const auto posed_samples = rebuilt->control_grid().points();
    for (std::size_t i = 0; i < posed_samples.size(); ++i) {
      Vec3f p = posed_samples[i] + Vec3f(u(rng), u(rng), u(rng));
      if (i % 50 == 0) p += Vec3f(0.3f, 0.1f, 0.0f);
      x.push_back(p);
    }
    std::size_t agree = 0, classified = 0;
    for (const Vec3f& p : x) {
      const float a = fast->signed_distance(p), b = rebuilt->signed_distance(p);
      agree += (a <= r) == (b <= r) && (a > 2 * r) == (b > 2 * r);
      // What measure() asks a posed shape (classify) is what its signed distance says.
      const auto w = fast->classify(p, r);
      classified += w.inside == (a <= r) && w.splash == (a > 2 * r);
    }
    EXPECT_EQ(classified, x.size()) << "t = " << time;
    const std::vector<std::uint8_t> ids(x.size(), 0), ctrl(x.size(), 1);
    const auto mf = metrics::measure(*fast, 0, x, ids, ctrl, r);
    const auto mr = metrics::measure(*rebuilt, 0, x, ids, ctrl, r);
    std::printf("walk t=%.3f: sign tests agree for %.2f %% of %zu points; E %.4f / %.4f %%, inside %.2f / %.2f %%, "
                "splash %.2f / %.2f %% (field / rebuilt)\n",
                time, 100.0 * double(agree) / double(x.size()), x.size(), mf.error_rate, mr.error_rate,
                100 * mf.inside_fraction, 100 * mr.inside_fraction, 100 * mf.splash_fraction, 100 * mr.splash_fraction);
    EXPECT_GE(double(agree), 0.99 * double(x.size())) << "t = " << time;
    EXPECT_DOUBLE_EQ(mf.error_rate, mr.error_rate);
    EXPECT_NEAR(mf.inside_fraction, mr.inside_fraction, 0.01);
    EXPECT_NEAR(mf.splash_fraction, mr.splash_fraction, 0.01);
  }
  std::printf("posed shape per frame (%zu samples): field %.4f s, rebuilt %.4f s\n", sk.bind_samples.size(),
              fast_s / times, rebuilt_s / times);
}

INSTANTIATE_TEST_SUITE_P(Files, Skinned, ::testing::ValuesIn(cases()),
                         [](const ::testing::TestParamInfo<SkinnedCase>& p) { return p.param.name; });

}  // namespace
}  // namespace ff::pipeline
