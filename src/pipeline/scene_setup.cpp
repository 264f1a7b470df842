#include "pipeline/scene_setup.h"

#include "pipeline/target_cache.h"
#include "io/load_mesh.h"
#include "core/parallel.h"
#include "sampling/skin_weights.h"
#include "control/cage_guard.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <cmath>

namespace ff::pipeline {
namespace fs = std::filesystem;
using nlohmann::json;

// At most 64 Mi cage weights (256 MiB) for one target's samples.
constexpr std::size_t kMaxCageWeights = std::size_t{64} << 20;

sampling::SamplingParams target_sampling(const scene::Scene& scene) {
  sampling::SamplingParams sp = scene.sampling;
  if (!(sp.spacing > 0.0f)) sp.spacing = scene.solver.spacing();
  sp.rest_density = scene.solver.rest_density;
  return sp;
}

Result<MeshPhase> prepare_mesh(const scene::Scene& scene, std::size_t t, const fs::path& mesh_path, const fs::path& cache_dir,
                               core::Progress& progress, const std::string& where) {
  scene::TargetSpec spec = scene.targets[t];
  spec.mesh = mesh_path;
  FF_TRY(TargetControls tc, sample_target_cached(spec, target_sampling(scene), static_cast<std::uint8_t>(t), cache_dir, progress));
  const auto fail = [&](const Error& e) {
    return Error{e.kind, where.empty() ? e.message : fmt::format("{}: {}", where, e.message)};
  };
  io::MeshLoadStats st;
  auto mesh = io::load_mesh(spec.mesh, io::LoadOptions{spec.transform}, &st);
  if (!mesh) return fail(mesh.error());
  auto shape = metrics::TargetShape::build(*mesh, tc.set.position, tc.set.spacing);
  if (!shape) return fail(shape.error());
  return MeshPhase{std::move(tc.set), std::move(*shape)};
}

Result<TargetSetup> setup_targets(const scene::Scene& scene, const std::vector<TargetGeometry>& geometry,
                                        const fs::path& cache_dir, const fs::path& report_dir,
                                        core::Progress& progress) {
  TargetSetup out;
  const sampling::SamplingParams sp = target_sampling(scene);
  for (std::size_t i = 0; i < scene.targets.size(); ++i) {
    FF_TRY(TargetControls tc, sample_target_cached(scene.targets[i], sp, static_cast<std::uint8_t>(i), cache_dir, progress));
    for (const auto& w : tc.report.warnings) spdlog::warn("target {}: {}", i, w);
    if (tc.from_cache)
      spdlog::info("target {}: {} control particles from the cache ({})", i, tc.set.size(), tc.cache_file.filename().string());
    else
      spdlog::info("target {}: {} control particles ({}, spacing {:g} m, {:.2f} s)", i, tc.set.size(),
                   sampling::method_name(tc.report.method), tc.report.spacing, tc.report.seconds);
    out.info.push_back({{"mesh", scene.targets[i].mesh.string()}, {"control_particles", tc.set.size()},
                        {"spacing", tc.set.spacing}, {"volume", geometry[i].volume}, {"cached", tc.from_cache},
                        {"controls", fs::relative(tc.cache_file, report_dir).string()}});
    out.control_count += tc.set.size();
    auto shape = metrics::TargetShape::build(geometry[i].mesh, tc.set.position, tc.set.spacing);
    if (!shape) return Error{shape.error().kind, fmt::format("targets[{}]: {}", i, shape.error().message)};
    TargetShapes ts;
    ts.from.push_back(-INFINITY);
    ts.shape.push_back(std::move(*shape));
    // Mesh swaps (morph): each swapped-in mesh is sampled (and cached) like a target of its own.
    std::vector<std::pair<double, sampling::ControlSet>> swaps;
    for (std::size_t k = 0; k < scene.targets[i].swaps.size(); ++k) {
      const scene::TargetSpec::Swap& swap = scene.targets[i].swaps[k];
      FF_TRY(MeshPhase sw, prepare_mesh(scene, i, swap.mesh, cache_dir, progress, fmt::format("targets[{}].morph[{}]", i, k)));
      spdlog::info("target {}: becomes {} at t = {} s ({} control particles)", i, swap.mesh.filename().string(), swap.time,
                   sw.set.size());
      ts.from.push_back(swap.time);
      ts.shape.push_back(std::move(sw.shape));
      swaps.emplace_back(swap.time, std::move(sw.set));
    }
    control::TargetMotion motion{scene.targets[i].keyframes, scene.targets[i].smooth(),
                                 0.5f * (geometry[i].box.min + geometry[i].box.max)};
    control::ControlTarget ct;
    ct.set = std::move(tc.set);
    ct.start = static_cast<double>(scene.targets[i].start);
    ct.motion = motion;
    ct.strength = control::StrengthTrack{scene.targets[i].strength};
    ct.swaps = std::move(swaps);
    if (const auto& skin = geometry[i].skin) {
      // Skin weights of the samples at the bind pose (sampling/skin_weights.h), and the posed target for the metrics.
      const auto how = skin->spec.weights == control::SkinWeightSource::Diffusion ? sampling::SkinWeighting::Diffusion
                                                                                 : sampling::SkinWeighting::ClosestPoint;
      FF_TRY(sampling::SampleSkin w, sampling::sample_skin_weights(geometry[i].mesh, *geometry[i].field, skin->skin,
                                                                  ct.set.position, ct.set.spacing, how));
      TargetShapes::Skinned sk{skin, geometry[i].mesh, skin->skin.joints, skin->skin.weights, ct.set.position,
                               w.joints, w.weights, ct.set.spacing,
                               std::make_shared<const sampling::MeshField>(*geometry[i].field), nullptr};
      // How the samples follow the posed mesh (control/skinning.h SampleFollow, control/mesh_anchors.h).
      const bool sheet = !geometry[i].field->encloses_volume();
      const std::size_t nv = geometry[i].mesh.vertices.size();
      const bool coarse = nv <= control::kCageMaxVertices &&
                          double(ct.set.size()) >= control::kCageSamplesPerVertex * double(nv) &&
                          ct.set.size() <= kMaxCageWeights / std::max<std::size_t>(1, nv);
      const bool anchored = skin->spec.follow == control::SampleFollow::Mesh ||
                            (skin->spec.follow == control::SampleFollow::Auto && (sheet || coarse));
      if (anchored) {
        const sampling::MeshField& field = *geometry[i].field;
        auto anchors = sheet ? control::anchor_to_triangles(geometry[i].mesh, skin->skin.joints, skin->skin.weights,
                                                            ct.set.position,
                                                            [&](std::size_t k) { return field.closest(ct.set.position[k]).triangle; })
                             : control::anchor_to_cage(geometry[i].mesh, skin->skin.joints, skin->skin.weights,
                                                       ct.set.position, kMaxCageWeights);
        if (!anchors) return Error{anchors.error().kind, fmt::format("targets[{}]: {}", i, anchors.error().message)};
        spdlog::info("target {}: the control samples follow the posed mesh ({})", i,
                     sheet ? "on its triangles" : fmt::format("in it as a cage of {} vertices", nv));
        if (!sheet) {
          // The cage's guard (control/cage_guard.h), from the mesh posed at kGuardPoses times of the clip.
          std::vector<std::vector<Vec3f>> poses;
          // (No clip: no poses, so no guard; only the bind pose is tried.)
          const double duration = skin->clip >= 0 && static_cast<std::size_t>(skin->clip) < skin->skin.clips.size()
                                      ? skin->skin.clips[static_cast<std::size_t>(skin->clip)].duration
                                      : 0.0;
          std::vector<io::Mat4f> K;
          control::PosedJoints joints;
          for (int k = 0; k < control::kGuardPoses && duration > 0.0; ++k) {
            skin->clip_joint_matrices(duration * std::min(double(k) / double(control::kGuardPoses - 1), 1.0 - 1e-9), K);
            joints.set(K, skin->spec.skinning);
            anchors->pose_vertices(joints, poses.emplace_back());
          }
          auto guard = control::guard_cage(*anchors, field, poses, ct.set.spacing);
          if (!guard) return Error{guard.error().kind, fmt::format("targets[{}]: {}", i, guard.error().message)};
          spdlog::info("target {}: {} of its {} control samples come near the surface at the clip's bends and are kept "
                       "inside the posed mesh ({:.1f} triangles each; {} where it folds over itself)",
                       i, guard->guarded, ct.set.size(), guard->guarded ? double(guard->triangles) / double(guard->guarded) : 0.0,
                       guard->folded);
        }
        sk.anchors = std::make_shared<const control::MeshAnchors>(std::move(*anchors));
        ct.anchors = sk.anchors;
      }
      ts.skinned = std::move(sk);
      ct.skin = skin;
      ct.skin_joints = std::move(w.joints);
      ct.skin_weights = std::move(w.weights);
    }
    out.shapes.push_back(std::move(ts));
    out.motions.push_back(motion);
    out.controls.push_back(std::move(ct));
  }
  return out;
}

namespace {

using JointIds = std::vector<std::array<std::uint16_t, io::kMaxInfluences>>;
using JointWeights = std::vector<std::array<float, io::kMaxInfluences>>;

control::PosedJoints joints_at(const TargetShapes::Skinned& sk, double time, control::SkinningMethod method) {
  std::vector<io::Mat4f> K;
  sk.skin->world_joint_matrices(time, K);
  control::PosedJoints joints;
  joints.set(std::move(K), method);
  return joints;
}

// `bind` points skinned by `joints` with their influences.
std::vector<Vec3f> skin_points(const control::PosedJoints& joints, const std::vector<Vec3f>& bind, const JointIds& ids,
                               const JointWeights& weights) {
  std::vector<Vec3f> x(bind.size());
  core::parallel_for(static_cast<std::int64_t>(x.size()), [&](std::int64_t i) {
    const auto k = static_cast<std::size_t>(i);
    x[k] = joints.apply(ids[k], weights[k], bind[k]);
  });
  return x;
}

// The bind mesh's vertices and the samples skinned by `joints`, then moved by `pose` (none: skinned only). Samples
// anchored to the mesh (control/mesh_anchors.h) are placed from the skinned vertices: the very ones the posed mesh has.
struct SkinnedPose {
  std::vector<Vec3f> vertices, samples;
};

SkinnedPose skin_pose(const TargetShapes::Skinned& sk, const control::PosedJoints& joints, const control::Pose* pose) {
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

}  // namespace

Result<metrics::TargetShape> posed_shape(const metrics::TargetShape& bind, const TargetShapes::Skinned& sk,
                                         const control::Pose& pose, double time) {
  SkinnedPose posed = skin_pose(sk, joints_at(sk, time, sk.skin->spec.skinning), &pose);
  // Measuring asks the posed mesh inside() and closest() only: a closed one skips the far field (MeshField::moved).
  FF_TRY(sampling::MeshField field, sk.bind_field->moved(posed.vertices, /*far_field=*/false));
  return metrics::TargetShape::posed(bind, std::move(field), posed.samples);
}

std::vector<Vec3f> posed_samples(const TargetShapes::Skinned& sk, double time, control::SkinningMethod method) {
  return skin_pose(sk, joints_at(sk, time, method), nullptr).samples;
}

Result<metrics::TargetShape> posed_shape_rebuilt(const TargetShapes::Skinned& sk, const control::Pose& pose, double time) {
  SkinnedPose posed = skin_pose(sk, joints_at(sk, time, sk.skin->spec.skinning), &pose);
  io::TriangleMesh mesh;
  mesh.triangles = sk.bind_mesh.triangles;
  mesh.vertices = std::move(posed.vertices);
  return metrics::TargetShape::build(mesh, posed.samples, sk.spacing);
}

ShapeMeasure measure_targets(const std::vector<TargetShapes>& shapes, const std::vector<control::TargetMotion>& motions,
                             double time, const sim::ParticleSet& p, float r, std::vector<std::uint8_t>& controlled) {
  ShapeMeasure out;
  if (shapes.empty()) return out;
  controlled.resize(p.size());
  for (std::size_t i = 0; i < p.size(); ++i) controlled[i] = p.bound_control[i] != kInvalidIndex;
  double w = 0, e = 0, ef = 0, eb = 0, efa = 0, in = 0, sp = 0;
  std::size_t ctrl = 0;
  for (std::size_t t = 0; t < shapes.size(); ++t) {
    // A moving target is measured in its rest frame, the fluid mapped into it by the inverse pose. A skinned one is
    // measured against its mesh posed at this time (LBS of its vertices, then the keyframed pose): a shape of its own.
    const control::Pose pose = motions[t].at(time);
    const bool skinned = shapes[t].skinned && (shapes[t].from.size() < 2 || time < shapes[t].from[1]);
    std::optional<metrics::TargetShape> posed;
    if (skinned) {
      auto s = posed_shape(shapes[t].shape[0], *shapes[t].skinned, pose, time);
      if (s) posed = std::move(*s);
      else spdlog::warn("target {}: the posed target has no shape at t = {} s ({}); measured at rest", t, time, s.error().message);
    }
    const metrics::TargetShape& shape = posed ? *posed : shapes[t].at(time);
    const auto m = posed ? metrics::measure(shape, static_cast<std::uint8_t>(t), p.position, p.target, controlled, r,
                                            Eigen::Affine3f::Identity(), 1.0f)
                         : metrics::measure(shape, static_cast<std::uint8_t>(t), p.position, p.target, controlled, r,
                                            pose.rest_from_world(), pose.scale);
    out.per_target.push_back(m);
    const double nc = static_cast<double>(shape.sample_count());
    ctrl += m.controlled;
    w += nc, e += nc * m.error_rate, ef += nc * m.e_fwd, eb += nc * m.e_bwd, efa += nc * m.e_fwd_all;
    in += nc * m.inside_fraction, sp += nc * m.splash_fraction;
  }
  out.controlled = ctrl;
  out.error_rate = e / w, out.e_fwd = ef / w, out.e_bwd = eb / w, out.e_fwd_all = efa / w;
  out.inside = in / w, out.splash = sp / w;
  return out;
}

}  // namespace ff::pipeline
