#include "pipeline/scene_setup.h"

#include "pipeline/target_cache.h"
#include "io/load_mesh.h"
#include "core/parallel.h"
#include "pose/skinned_target.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <cmath>

namespace ff::pipeline {
namespace fs = std::filesystem;
using nlohmann::json;

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
    if (const auto& th = geometry[i].thickness) {  // its thinnest walls (sampling/thickness.h), and in spacings
      const Vec3f& w = th->where;
      out.info.back()["thinnest_wall"] = {{"m", th->thinnest}, {"spacings", th->thinnest / tc.set.spacing},
                                          {"near", {w.x(), w.y(), w.z()}},
                                          {"median_m", std::isfinite(th->median) ? json(th->median) : json(nullptr)}};
    }
    if (const auto warning = thin_wall_warning(scene, i, geometry[i])) spdlog::warn("{}", *warning);
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
    pose::TargetMotion motion{scene.targets[i].keyframes, scene.targets[i].smooth(),
                                 0.5f * (geometry[i].box.min + geometry[i].box.max)};
    control::ControlTarget ct;
    ct.set = std::move(tc.set);
    ct.start = static_cast<double>(scene.targets[i].start);
    ct.motion = motion;
    ct.strength = control::StrengthTrack{scene.targets[i].strength};
    ct.swaps = std::move(swaps);
    if (const auto& skin = geometry[i].skin) {
      FF_TRY(pose::SkinnedTarget sk, pose::bind_skinned_target(i, skin, geometry[i].mesh, *geometry[i].field,
                                                               ct.set.position, ct.set.spacing));
      ct.skin = skin;
      ct.skin_joints = sk.sample_joints;
      ct.skin_weights = sk.sample_weights;
      ct.anchors = sk.anchors;
      ts.skinned = std::move(sk);
    }
    out.shapes.push_back(std::move(ts));
    out.motions.push_back(motion);
    out.controls.push_back(std::move(ct));
  }
  return out;
}

Result<metrics::TargetShape> posed_shape(const metrics::TargetShape& bind, const pose::SkinnedTarget& sk,
                                         const pose::Pose& pose, double time) {
  pose::SkinnedPose posed = pose::skin_pose(sk, pose::joints_at(*sk.skin, time, sk.skin->spec.skinning), &pose);
  // Measuring asks the posed mesh inside() and closest() only: a closed one skips the far field (MeshField::moved).
  FF_TRY(sampling::MeshField field, sk.bind_field->moved(posed.vertices, /*far_field=*/false));
  return metrics::TargetShape::posed(bind, std::move(field), posed.samples);
}

Result<metrics::TargetShape> posed_shape_rebuilt(const pose::SkinnedTarget& sk, const pose::Pose& pose, double time) {
  pose::SkinnedPose posed = pose::skin_pose(sk, pose::joints_at(*sk.skin, time, sk.skin->spec.skinning), &pose);
  io::TriangleMesh mesh;
  mesh.triangles = sk.bind_mesh.triangles;
  mesh.vertices = std::move(posed.vertices);
  return metrics::TargetShape::build(mesh, posed.samples, sk.spacing);
}

ShapeMeasure measure_targets(const std::vector<TargetShapes>& shapes, const std::vector<pose::TargetMotion>& motions,
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
    const pose::Pose pose = motions[t].at(time);
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
