#include "pose/skinned_target.h"

#include "core/parallel.h"
#include "pose/cage_guard.h"
#include "pose/skin_weights.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>

namespace ff::pose {
namespace {

using JointIds = std::vector<std::array<std::uint16_t, io::kMaxInfluences>>;
using JointWeights = std::vector<std::array<float, io::kMaxInfluences>>;

/// Prefixes an error with the target it is about.
Error of_target(std::size_t index, const Error& e) {
  return Error{e.kind, fmt::format("targets[{}]: {}", index, e.message)};
}

/// Whether the samples follow the posed mesh (SampleFollow; Auto: an open sheet, or a coarse closed mesh).
bool follows_mesh(const TargetSkin& skin, bool sheet, std::size_t vertices, std::size_t samples) {
  const bool coarse = vertices <= kCageMaxVertices && double(samples) >= kCageSamplesPerVertex * double(vertices) &&
                      samples <= kMaxCageWeights / std::max<std::size_t>(1, vertices);
  return skin.spec.follow == SampleFollow::Mesh || (skin.spec.follow == SampleFollow::Auto && (sheet || coarse));
}

/// The cage's guard (pose/cage_guard.h), from the mesh posed at kGuardPoses times of the clip. No clip: no poses, so
/// no guard; only the bind pose is tried.
Status guard_over_clip(std::size_t index, const TargetSkin& skin, MeshAnchors& anchors, const sampling::MeshField& field,
                       std::size_t samples, float spacing) {
  std::vector<std::vector<Vec3f>> poses;
  const double duration = skin.clip >= 0 && static_cast<std::size_t>(skin.clip) < skin.skin.clips.size()
                              ? skin.skin.clips[static_cast<std::size_t>(skin.clip)].duration
                              : 0.0;
  std::vector<io::Mat4f> K;
  PosedJoints joints;
  for (int k = 0; k < kGuardPoses && duration > 0.0; ++k) {
    skin.clip_joint_matrices(duration * std::min(double(k) / double(kGuardPoses - 1), 1.0 - 1e-9), K);
    joints.set(K, skin.spec.skinning);
    anchors.pose_vertices(joints, poses.emplace_back());
  }
  auto guard = guard_cage(anchors, field, poses, spacing);
  if (!guard) return of_target(index, guard.error());
  spdlog::info("target {}: {} of its {} control samples come near the surface at the clip's bends and are kept "
               "inside the posed mesh ({:.1f} triangles each; {} where it folds over itself)",
               index, guard->guarded, samples, guard->guarded ? double(guard->triangles) / double(guard->guarded) : 0.0,
               guard->folded);
  return {};
}

// `bind` points skinned by `joints` with their influences.
std::vector<Vec3f> skin_points(const PosedJoints& joints, const std::vector<Vec3f>& bind, const JointIds& ids,
                               const JointWeights& weights) {
  std::vector<Vec3f> x(bind.size());
  core::parallel_for(static_cast<std::int64_t>(x.size()), [&](std::int64_t i) {
    const auto k = static_cast<std::size_t>(i);
    x[k] = joints.apply(ids[k], weights[k], bind[k]);
  });
  return x;
}

}  // namespace

Result<SkinnedTarget> bind_skinned_target(std::size_t index, const std::shared_ptr<const TargetSkin>& skin,
                                          const io::TriangleMesh& mesh, const sampling::MeshField& field,
                                          const std::vector<Vec3f>& samples, float spacing) {
  // Skin weights of the samples at the bind pose (pose/skin_weights.h).
  const auto how = skin->spec.weights == SkinWeightSource::Diffusion ? SkinWeighting::Diffusion
                                                                     : SkinWeighting::ClosestPoint;
  FF_TRY(SampleSkin w, sample_skin_weights(mesh, field, skin->skin, samples, spacing, how));
  SkinnedTarget sk{skin,      mesh,    skin->skin.joints, skin->skin.weights, samples, std::move(w.joints),
                   std::move(w.weights), spacing, std::make_shared<const sampling::MeshField>(field), nullptr};
  const bool sheet = !field.encloses_volume();
  const std::size_t nv = mesh.vertices.size();
  if (!follows_mesh(*skin, sheet, nv, samples.size())) return sk;
  auto anchors = sheet ? anchor_to_triangles(mesh, skin->skin.joints, skin->skin.weights, samples,
                                             [&](std::size_t k) { return field.closest(samples[k]).triangle; })
                       : anchor_to_cage(mesh, skin->skin.joints, skin->skin.weights, samples, kMaxCageWeights);
  if (!anchors) return of_target(index, anchors.error());
  spdlog::info("target {}: the control samples follow the posed mesh ({})", index,
               sheet ? "on its triangles" : fmt::format("in it as a cage of {} vertices", nv));
  if (!sheet) FF_CHECK(guard_over_clip(index, *skin, *anchors, field, samples.size(), spacing));
  sk.anchors = std::make_shared<const MeshAnchors>(std::move(*anchors));
  return sk;
}

PosedJoints joints_at(const TargetSkin& skin, double time, SkinningMethod method) {
  std::vector<io::Mat4f> K;
  skin.world_joint_matrices(time, K);
  PosedJoints joints;
  joints.set(std::move(K), method);
  return joints;
}

SkinnedPose skin_pose(const SkinnedTarget& sk, const PosedJoints& joints, const Pose* pose) {
  SkinnedPose out;
  out.vertices = skin_points(joints, sk.bind_mesh.vertices, sk.mesh_joints, sk.mesh_weights);
  if (sk.anchors) {
    out.samples.resize(sk.bind_samples.size());
    core::parallel_for(static_cast<std::int64_t>(out.samples.size()), [&](std::int64_t i) {
      out.samples[static_cast<std::size_t>(i)] = sk.anchors->place(static_cast<std::size_t>(i), out.vertices);
    });
  } else {
    out.samples = skin_points(joints, sk.bind_samples, sk.sample_joints, sk.sample_weights);
  }
  if (pose)
    for (auto* points : {&out.vertices, &out.samples})
      for (Vec3f& x : *points) x = pose->apply(x);
  return out;
}

std::vector<Vec3f> posed_samples(const SkinnedTarget& sk, double time, SkinningMethod method) {
  return skin_pose(sk, joints_at(*sk.skin, time, method), nullptr).samples;
}

}  // namespace ff::pose
