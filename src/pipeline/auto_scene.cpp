#include "pipeline/auto_scene.h"

#include "io/skin.h"

#include "io/load_mesh.h"
#include "pipeline/run_budget.h"
#include "sampling/mesh_field.h"
#include "sampling/samplers.h"
#include "pose/target_motion.h"
#include "sim/emitter.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

namespace ff::pipeline {

Result<std::shared_ptr<const pose::TargetSkin>> load_target_skin(const scene::TargetSpec& spec, const io::TriangleMesh& mesh,
                                                                    std::size_t i) {
  const auto fail = [&](const Error& e) { return Error{e.kind, fmt::format("targets[{}].animation: {}", i, e.message)}; };
  auto loaded = io::load_skin(spec.mesh, mesh, spec.transform);
  if (!loaded) return fail(loaded.error());
  if (!loaded->has_value())
    return fail(input_error(fmt::format("{} has no skin (no bones), so it has no clip '{}' to play",
                                        spec.mesh.filename().string(), spec.animation.clip)));
  auto skin = std::make_shared<pose::TargetSkin>();
  skin->skin = std::move(**loaded);
  auto clip = skin->skin.find_clip(spec.animation.clip);
  if (!clip) return fail(Error{clip.error().kind, fmt::format("{}: {}", spec.mesh.filename().string(), clip.error().message)});
  skin->clip = static_cast<int>(*clip);
  skin->transform = io::transform_matrix(spec.transform);
  skin->spec = spec.animation;
  for (const auto& w : skin->skin.warnings) spdlog::warn("target {}: {}", i, w);
  const auto& c = skin->skin.clips[*clip];
  const double seam = spec.animation.loop ? clip_seam(*skin, mesh) : 0.0;
  skin->pingpong = spec.animation.loop && c.duration > 0.0 && (spec.animation.wrap == pose::ClipWrap::PingPong ||
                                           (spec.animation.wrap == pose::ClipWrap::Auto && seam > pose::kClipSeamTolerance));
  spdlog::info("target {}: skinned, {} joints, clip '{}' ({:.3g} s, {} channels{})", i, skin->skin.joint_nodes.size(),
               c.name, c.duration, c.channels.size(),
               !spec.animation.loop ? "" : skin->pingpong ? ", played back and forth" : ", looped");
  if (skin->pingpong && spec.animation.wrap == pose::ClipWrap::Auto)
    spdlog::info("target {}: clip '{}' ends {:.0f} % of the mesh's size away from where it starts, a jump the liquid "
                 "cannot follow: it plays backwards to its start, then forwards again (\"wrap\": \"repeat\" jumps)",
                 i, c.name, 100.0 * seam);
  return std::shared_ptr<const pose::TargetSkin>(std::move(skin));
}

Result<std::vector<TargetGeometry>> load_target_meshes(const scene::Scene& scene) {
  std::vector<TargetGeometry> out;
  for (std::size_t i = 0; i < scene.targets.size(); ++i) {
    io::MeshLoadStats st;
    auto mesh = io::load_mesh(scene.targets[i].mesh, io::LoadOptions{scene.targets[i].transform}, &st);
    if (!mesh) return Error{mesh.error().kind, fmt::format("targets[{}]: {}", i, mesh.error().message)};
    auto field = sampling::MeshField::build(*mesh);
    if (!field) return Error{field.error().kind, fmt::format("targets[{}]: {}", i, field.error().message)};
    spdlog::info("target {}: {} ({} vertices, {} triangles, {} degenerate dropped)", i,
                 scene.targets[i].mesh.filename().string(), mesh->vertices.size(), mesh->triangles.size(),
                 st.dropped_degenerate);
    TargetGeometry g;
    g.volume = field->encloses_volume() ? field->volume() : 0.0;
    g.area = field->area();
    g.box = field->bounds();
    if (scene.targets[i].animation.active()) {
      FF_TRY(g.skin, load_target_skin(scene.targets[i], *mesh, i));
    }
    g.mesh = std::move(*mesh);
    g.field = std::move(*field);
    out.push_back(std::move(g));
  }
  return out;
}

double clip_seam(const pose::TargetSkin& skin, const io::TriangleMesh& mesh) {
  if (skin.clip < 0 || static_cast<std::size_t>(skin.clip) >= skin.skin.clips.size() || mesh.vertices.empty() ||
      skin.skin.joints.size() != mesh.vertices.size() || skin.skin.weights.size() != mesh.vertices.size())
    return 0.0;
  const double duration = skin.skin.clips[static_cast<std::size_t>(skin.clip)].duration;
  std::vector<io::Mat4f> first, last;
  skin.clip_joint_matrices(0.0, first);
  skin.clip_joint_matrices(duration, last);
  Eigen::AlignedBox3f box;
  double jump = 0.0;
  for (std::size_t v = 0; v < mesh.vertices.size(); ++v) {
    const Vec3f& x = mesh.vertices[v];
    box.extend(x);
    const Vec3f a = io::skin_point(first, skin.skin.joints[v], skin.skin.weights[v], x);
    const Vec3f b = io::skin_point(last, skin.skin.joints[v], skin.skin.weights[v], x);
    jump = std::max(jump, static_cast<double>((a - b).norm()));
  }
  const double size = box.diagonal().norm();
  return size > 0.0 && std::isfinite(jump) ? jump / size : 0.0;
}

double posed_volume_share(const pose::TargetSkin& skin, const io::TriangleMesh& mesh, int samples) {
  const double bind = io::signed_volume(mesh);
  if (!(std::abs(bind) > 0.0) || skin.clip < 0 || static_cast<std::size_t>(skin.clip) >= skin.skin.clips.size()) return 1.0;
  const double duration = skin.skin.clips[static_cast<std::size_t>(skin.clip)].duration;
  io::TriangleMesh posed = mesh;
  std::vector<io::Mat4f> K;
  pose::PosedJoints joints;
  double share = 1.0;
  for (int k = 0; k < samples; ++k) {
    // Scene times whose clip times τ = k/(samples−1) of the clip (the last just short of its end, where a loop wraps).
    const double tau = duration * std::min(double(k) / double(std::max(1, samples - 1)), 1.0 - 1e-9);
    skin.world_joint_matrices(skin.spec.start + tau / skin.spec.speed, K);
    joints.set(K, skin.spec.skinning);
    for (std::size_t v = 0; v < mesh.vertices.size(); ++v)
      posed.vertices[v] = joints.apply(skin.skin.joints[v], skin.skin.weights[v], mesh.vertices[v]);
    share = std::min(share, io::signed_volume(posed) / bind);
  }
  return std::isfinite(share) ? std::max(share, 0.0) : 1.0;
}

namespace {

// The refusal of a spacing dc that would make about `count` control samples of target k, over the limit.
Error too_many_samples(const scene::Scene& s, std::size_t k, float dc, double count) {
  return param_error(fmt::format("targets[{}]: a spacing of {:g} m would make about {:.3g} control samples, more than "
                                 "the limit of {} (sampling.max_samples); increase solver.particle_radius or "
                                 "sampling.spacing",
                                 k, dc, count, s.sampling.max_samples));
}

// The count the memory limit allows: each particle costs about one fluid particle and one control sample
// (run_budget.h's model) within half the limit, the other half left for the SDF grids and for the blue-noise
// sampler's extra samples on thin walls, which check_run_budget counts and refuses beyond the limit.
double count_memory_allows(const scene::Scene& s) {
  const double limit = memory_limit_mib(s, std::nullopt);
  return std::max(0.0, (0.5 * limit - kBaseMib) * 1024.0 / (kFluidKib + kSampleKib));
}

// The particle radius from the targets' volume (or area): d³ per sample (the blue-noise count is V/d³); an open
// sheet is sampled by its area instead. When the scene left the count automatic (auto_resolution), the count
// rises from auto_count until the thinnest wall of any target is kWallSpacings spacings across, up to
// max_auto_count and what the memory limit allows (scene.sizing records which). A thick shape keeps auto_count.
Status size_particles(scene::Scene& s, const std::vector<TargetGeometry>& targets, double volume, double area) {
  const double n = static_cast<double>(s.sampling.auto_count);
  const double d_volume = volume > 0.0 ? std::cbrt(volume / n) : std::sqrt(area / n);
  if (!(d_volume > 0.0) || !std::isfinite(d_volume))
    return input_error("the targets have no volume and no area to size the particles by");
  scene::AutoSizing& z = s.sizing;
  z = scene::AutoSizing{};
  z.count_for_volume = z.count = n;
  for (std::size_t k = 0; k < targets.size(); ++k)
    if (const auto& th = targets[k].thickness; th && (z.target < 0 || th->thinnest < z.wall))
      z.target = static_cast<int>(k), z.wall = th->thinnest;
  double d = d_volume;
  if (z.target >= 0 && volume > 0.0 && z.wall > 0.0 && z.wall < kWallSpacings * d_volume) {
    // The count goes as 1/d³: the spacing a wall needs, as a count.
    z.count_for_walls = n * std::pow(kWallSpacings * d_volume / z.wall, 3.0);
    // A skinned target keeps auto_count: the walking demo character at the ~21.7k its limbs ask for held 95.6 %
    // inside at its worst frame (3.0 % splash) where 10k holds ≥ 98 % (issue 44, bench/RESULTS.md), so a count
    // raised for its walls would cost it its shape.
    const bool skinned = std::any_of(targets.begin(), targets.end(), [](const TargetGeometry& t) { return bool(t.skin); });
    if (skinned && s.auto_resolution) z.limited_by = "skinned";
    if (s.auto_resolution && !skinned) {
      const double budget = std::max(n, double(s.sampling.max_auto_count)), memory = std::max(n, count_memory_allows(s));
      z.count = std::min({z.count_for_walls, budget, memory});
      if (z.count < z.count_for_walls) z.limited_by = budget <= memory ? "sampling.max_auto_count" : "memory";
      d = d_volume * std::cbrt(n / z.count);
    }
  }
  s.solver.particle_radius = static_cast<float>(0.5 * d);
  FF_CHECK(s.solver.validate());
  if (z.count > n) {
    const auto& w = targets[static_cast<std::size_t>(z.target)].thickness->where;
    spdlog::info("target {}: walls {:.3g} m thin near ({:.3g}, {:.3g}, {:.3g}): about {:.3g} particles put {:.1f} spacings "
                 "across them (sampling.auto_count {} would put {:.1f})",
                 z.target, z.wall, w.x(), w.y(), w.z(), z.count, z.wall / d, s.sampling.auto_count, z.wall / d_volume);
  }
  return {};
}


// Target k's fluid volume: kFluidCellShare of the lattice cells its solid covers at the control spacing dc
// (sampling::lattice_cells), less what the sparse-sampling options remove, and for a skinned target, what its
// tightest pose keeps; an open sheet's is one layer of samples.
// Sets t.volume and adds it to `volume` (a target with neither volume nor area is left as it was, and adds nothing).
Status size_target_fluid(const scene::Scene& s, std::size_t k, TargetGeometry& t, float dc, double& volume) {
  if (!(t.volume > 0.0)) {
    // An open sheet (glTF2/simple_skin, a cloth, a terrain patch) is sampled as one layer of surface samples:
    // its fluid is one particle per sample, a layer one spacing thick that takes the sheet's shape.
    if (t.area > 0.0) {
      const double count = sampling::estimate_sample_count(false, 0.0, t.area, dc);
      if (count > 1.5 * double(s.sampling.max_samples)) return too_many_samples(s, k, dc, count);
      t.volume = count * (1.0 - s.sampling.sparse.drop_fraction) * double(dc) * dc * dc;
      volume += t.volume;
    }
    return {};
  }
  // The voxel grid below grows as 1/dc³: refuse a spacing that would make more samples than the sampler
  // will accept before allocating it.
  if (const double rough = sampling::estimate_sample_count(true, t.volume, t.area, dc);
      rough > 1.5 * double(s.sampling.max_samples))
    return too_many_samples(s, k, dc, rough);
  // The cells the solid covers, counted in part (sampling::lattice_cells), less the drop boxes: a count of the lattice
  // points inside instead reads only the whole layers that fit across a part a few spacings thick (the 3 cm gear at
  // dc = 6.1 mm: 4 of its 4.9), and such parts' fluid came out at 0.6–0.7 of their samples, with holes.
  const sampling::LatticeCells cells = sampling::lattice_cells(*t.field, dc);
  double covered = 0.0;
  for (std::size_t i = 0; i < cells.point.size(); ++i) {
    const Vec3f& x = cells.point[i];
    bool dropped = false;
    for (const auto& b : s.sampling.sparse.drop_boxes)
      dropped = dropped || ((x.array() >= b.min.array()).all() && (x.array() <= b.max.array()).all());
    covered += dropped ? 0.0 : double(cells.share[i]);
  }
  t.cells_volume = covered * (1.0 - s.sampling.sparse.drop_fraction) * double(dc) * dc * dc;
  t.volume = kFluidCellShare * t.cells_volume;
  if (t.skin && t.skin->skin.joints.size() == t.mesh.vertices.size()) {
    // A skinned mesh can lose volume at its bends (linear blend skinning of a coarse mesh cuts their corners),
    // and the liquid keeps its own: sized to the bind volume, what the tightest pose has no room for is pushed
    // out (huesitos.fbx keeps 88 % at worst). Sized to that pose, it fits at every one.
    if (const double share = posed_volume_share(*t.skin, t.mesh); share < 1.0) {
      spdlog::info("target {}: its posed mesh keeps {:.1f} % of its bind volume at the clip's tightest pose: the "
                   "fluid is sized to that",
                   k, 100.0 * share);
      t.volume *= share;
    }
  }
  volume += t.volume;
  return {};
}

// The highest point of `mesh` over the rectangle [lo, hi] of the xz plane: each triangle clipped to the rectangle
// (Sutherland–Hodgman against its four sides), its highest clipped vertex. −∞ when no triangle lies over it.
float highest_over(const io::TriangleMesh& mesh, const Eigen::Vector2f& lo, const Eigen::Vector2f& hi) {
  float top = -std::numeric_limits<float>::infinity();
  std::vector<Vec3f> poly, next;
  for (const auto& tri : mesh.triangles) {
    poly = {mesh.vertices[tri[0]], mesh.vertices[tri[1]], mesh.vertices[tri[2]]};
    // Sides: x ≥ lo.x, x ≤ hi.x, z ≥ lo.y, z ≤ hi.y; inside(p) ≥ 0.
    for (int side = 0; side < 4 && !poly.empty(); ++side) {
      const int axis = side < 2 ? 0 : 2;
      const float bound = side == 0 ? lo.x() : side == 1 ? hi.x() : side == 2 ? lo.y() : hi.y();
      const float sign = side % 2 == 0 ? 1.0f : -1.0f;
      const auto inside = [&](const Vec3f& p) { return sign * (p[axis] - bound); };
      next.clear();
      for (std::size_t i = 0; i < poly.size(); ++i) {
        const Vec3f& a = poly[i];
        const Vec3f& b = poly[(i + 1) % poly.size()];
        const float fa = inside(a), fb = inside(b);
        if (fa >= 0.0f) next.push_back(a);
        if ((fa >= 0.0f) != (fb >= 0.0f)) next.push_back(a + (fa / (fa - fb)) * (b - a));
      }
      poly.swap(next);
    }
    for (const Vec3f& p : poly) top = std::max(top, p.y());
  }
  return top;
}

// Where target k's column starts: a spacing over the highest point of any target under its footprint [lo, hi], at most
// over the top of k's box. For most shapes that is the top of the box; a container whose footprint's middle looks down
// on its floor (an open box, a bowl) gets its fluid inside it: poured from above its rim, the open box's fluid struck
// the floor at ~4 m/s, ran up the walls and was held there, over-full toward the rim, and the floor kept a hole 20
// spacings across whatever the fluid's share (bench/RESULTS.md, "Detail at scale, ninth part"). Every target counts,
// so a column never starts inside another target it used to fall onto. A moving or skinned target is placed by its
// bind pose, which need not be its pose at the start, and a footprint over none of the targets has nothing to stand
// on: both keep the top of the box.
float column_base(const scene::Scene& s, const std::vector<TargetGeometry>& targets, std::size_t k,
                  const Eigen::Vector2f& lo, const Eigen::Vector2f& hi) {
  const TargetGeometry& t = targets[k];
  const scene::TargetSpec& spec = s.targets[k];
  if (t.skin || !spec.keyframes.empty() || !spec.swaps.empty()) return t.box.max.y();
  float under = -std::numeric_limits<float>::infinity();
  for (const auto& other : targets) under = std::max(under, highest_over(other.mesh, lo, hi));
  return std::isfinite(under) ? std::min(under, t.box.max.y()) : t.box.max.y();
}

// A fluid column over the middle of each target's footprint holding the target's volume, a spacing over where
// column_base says it stands. Returns the particles each column is to hold (its volume in cells of d³), for
// fit_columns.
std::vector<std::size_t> place_fluid_columns(scene::Scene& s, const std::vector<TargetGeometry>& targets, float d) {
  std::vector<std::size_t> counts;
  for (std::size_t k = 0; k < targets.size(); ++k) {
    const TargetGeometry& t = targets[k];
    if (!(t.volume > 0.0)) continue;
    const Vec3f ext = t.box.max - t.box.min, mid = 0.5f * (t.box.min + t.box.max);
    float fx = std::max(0.7f * ext.x(), 4.0f * d), fz = std::max(0.7f * ext.z(), 4.0f * d);
    float h = static_cast<float>(t.volume / (double(fx) * fz));
    // A very thin target would make a needle: widen the column to at most its own height.
    if (h > 2.0f * std::max(fx, fz)) {
      const float a = std::cbrt(static_cast<float>(t.volume) / 2.0f);
      fx = fz = a;
      h = 2.0f * a;
    }
    const float base = column_base(s, targets, k, Eigen::Vector2f(mid.x() - 0.5f * fx, mid.z() - 0.5f * fz),
                                   Eigen::Vector2f(mid.x() + 0.5f * fx, mid.z() + 0.5f * fz));
    sim::FluidSource src;
    src.shape = sim::FluidSource::Shape::Box;
    src.min = Vec3f(mid.x() - 0.5f * fx, base + d, mid.z() - 0.5f * fz);
    src.max = Vec3f(mid.x() + 0.5f * fx, base + d + h, mid.z() + 0.5f * fz);
    if (base < t.box.max.y())
      spdlog::info("target {}: its fluid starts inside it, {:.3g} m below its top (over the highest point under the "
                   "column)", k, t.box.max.y() - base);
    s.fluid.push_back(src);
    counts.push_back(static_cast<std::size_t>(std::llround(t.volume / (double(d) * d * d))));
  }
  return counts;
}

// Each automatic column cut to hold its count exactly on the domain's lattice (sim::boxes_for_count): a box
// fills the whole layers that fit in it, and the columns over flat targets are only a few layers tall. A column
// whose footprint overlaps one placed before it starts a spacing above it (fill_sources counts a shared lattice
// point once, so overlapping columns came out short), and an automatic domain grows to keep 2 H_c above the top.
void fit_columns(scene::Scene& s, const std::vector<std::size_t>& counts, float hc) {
  const float d = s.solver.spacing();
  std::vector<sim::FluidSource> fitted;
  for (std::size_t c = 0; c < s.fluid.size(); ++c) {
    sim::FluidSource column = s.fluid[c];
    // Until it overlaps none: a lift over one box can reach one the pass has already checked.
    for (bool lifted = true; lifted;) {
      lifted = false;
      for (const auto& f : fitted) {
        const bool overlaps = f.min.x() < column.max.x() && column.min.x() < f.max.x() && f.min.z() < column.max.z() &&
                              column.min.z() < f.max.z() && f.min.y() < column.max.y() && column.min.y() < f.max.y();
        if (overlaps) {
          const float lift = f.max.y() + d - column.min.y();
          column.min.y() += lift, column.max.y() += lift;
          lifted = true;
        }
      }
    }
    if (s.auto_domain) s.domain.max.y() = std::max(s.domain.max.y(), column.max.y() + 2.0f * hc);
    auto boxes = sim::boxes_for_count(column, s.domain, s.solver.particle_radius, counts[c]);
    if (boxes.empty()) boxes.push_back(column);  // its footprint holds no lattice point: fill_sources says so
    // The part layer can stand a little above the column's box, and a narrow footprint's whole layers well above it.
    for (const auto& b : boxes)
      if (s.auto_domain) s.domain.max.y() = std::max(s.domain.max.y(), b.max.y() + 2.0f * hc);
    fitted.insert(fitted.end(), boxes.begin(), boxes.end());
  }
  s.fluid = std::move(fitted);
}

// Extends `box` by target t's box at every keyframe of its motion and, for a skinned target, by its posed mesh at 129
// times of the clip's first play.
void extend_by_target_path(Aabb& box, const scene::TargetSpec& spec, const TargetGeometry& t) {
  box.extend(t.box.min), box.extend(t.box.max);
  // A keyframed target sweeps a path: the domain holds its box at every keyframe.
  const pose::TargetMotion motion{spec.keyframes, spec.smooth(), 0.5f * (t.box.min + t.box.max)};
  for (const auto& key : motion.keys) {
    const pose::Pose pose = motion.at(key.time);
    for (int c = 0; c < 8; ++c)
      box.extend(pose.apply(Vec3f(c & 1 ? t.box.max.x() : t.box.min.x(), c & 2 ? t.box.max.y() : t.box.min.y(),
                                  c & 4 ? t.box.max.z() : t.box.min.z())));
  }
  // A skinned target's limbs swing out of its bind box (a walk's feet and hands by 0.2 m): the domain holds its
  // posed mesh at 129 times of the clip's first play (then the keyframed pose at that time), so no limb meets a
  // wall. Without this the walking character pressed its hands and feet flat against the walls, and 10 % of its
  // fluid stayed there.
  if (t.skin) {
    const pose::TargetSkin& sk = *t.skin;
    const auto& clip = sk.skin.clips[static_cast<std::size_t>(sk.clip)];
    const double span = sk.spec.start + clip.duration / sk.spec.speed;
    std::vector<io::Mat4f> K;
    for (int q = 0; q <= 128; ++q) {
      const double time = span * q / 128.0;
      sk.world_joint_matrices(time, K);
      const pose::Pose pose = motion.at(time);
      for (std::size_t v = 0; v < t.mesh.vertices.size(); ++v)
        box.extend(pose.apply(io::skin_point(K, sk.skin.joints[v], sk.skin.weights[v], t.mesh.vertices[v])));
    }
  }
}

// The domain: the targets' paths and the fluid, 2 H_c of margin at the sides and top, H_c below.
void size_domain(scene::Scene& s, const std::vector<TargetGeometry>& targets, float hc) {
  Aabb box;
  for (std::size_t k = 0; k < targets.size(); ++k) extend_by_target_path(box, s.targets[k], targets[k]);
  for (const auto& f : s.fluid) {
    if (f.shape == sim::FluidSource::Shape::Box) {
      box.extend(f.min), box.extend(f.max);
    } else {
      box.extend(f.center - Vec3f::Constant(f.radius)), box.extend(f.center + Vec3f::Constant(f.radius));
    }
  }
  const float margin = 2.0f * hc;
  s.domain.min = box.min - Vec3f(margin, 0.0f, margin);
  s.domain.min.y() = std::min(box.min.y() - hc, box.min.y());
  for (const auto& t : targets) s.domain.min.y() = std::min(s.domain.min.y(), t.box.min.y() - hc);
  s.domain.max = box.max + Vec3f(margin, margin, margin);
}

// Targets far outside human scale were most likely modelled in other units (many tools export characters in
// centimetres): they run as they are, and one line says which scale would make them metres.
void suggest_unit_scale(const std::vector<TargetGeometry>& targets) {
  Aabb box;
  for (const auto& t : targets) box.extend(t.box.min), box.extend(t.box.max);
  const double size = box.size().maxCoeff();
  if (!(size > 50.0) || !std::isfinite(size)) return;
  const double scale = size * 0.01 <= 50.0 ? 0.01 : 0.001;
  spdlog::warn("the targets are {:.0f} m across, far outside human scale: if the file is in {}, add \"scale\": {:g} to "
               "each target (forming takes longer the larger the shape)",
               size, scale == 0.01 ? "centimetres" : "millimetres", scale);
}

// Each closed target's thinnest walls (sampling/thickness.h), for thin_wall_warning and report.json.
void measure_walls(std::vector<TargetGeometry>& targets) {
  for (auto& t : targets)
    if (t.field && t.volume > 0.0) t.thickness = sampling::measure_thickness(*t.field, t.mesh);  // not an open sheet
}

}  // namespace

Status complete_scene(scene::Scene& s, std::vector<TargetGeometry>& targets) {
  if (targets.empty()) return {};
  double volume = 0.0, area = 0.0;
  for (const auto& t : targets) volume += t.volume, area += t.area;
  suggest_unit_scale(targets);
  measure_walls(targets);
  if (s.auto_radius) FF_CHECK(size_particles(s, targets, volume, area));
  const float d = s.solver.spacing(), hc = s.sampling.support_factor * d;
  if (s.fluid.empty()) {
    // The fluid matches the volume the control samples will stand for, less kFluidCellShare's margin: the lattice cells
    // the solid covers at the spacing (the union of overlapping parts, not the sum a divergence-theorem volume
    // gives), less what the sparse-sampling options remove.
    const float dc = s.sampling.spacing > 0.0f ? s.sampling.spacing : d;
    // Sizes are checked before anything is allocated for them (a tiny particle_radius would exhaust the memory).
    volume = 0.0;
    for (std::size_t k = 0; k < targets.size(); ++k) FF_CHECK(size_target_fluid(s, k, targets[k], dc, volume));
  }
  std::vector<std::size_t> column_counts;
  if (s.fluid.empty()) {
    if (!(volume > 0.0))
      return input_error("the targets have no volume and no area, so the fluid cannot be sized from them: add a \"fluid\" list");
    column_counts = place_fluid_columns(s, targets, d);
  }
  if (s.auto_domain) size_domain(s, targets, hc);
  if (!column_counts.empty()) fit_columns(s, column_counts, hc);
  return s.validate();
}

std::optional<std::string> thin_wall_warning(const scene::Scene& s, std::size_t k, const TargetGeometry& t) {
  const double d = s.sampling.spacing > 0.0f ? s.sampling.spacing : s.solver.spacing();
  // A hair under 3 spacings is the automatic count's own rounding (its spacing is a float radius): not a warning.
  if (!t.thickness || t.thickness->thinnest >= (kWallSpacings - 1e-3) * d) return std::nullopt;
  const double need = t.thickness->thinnest / kWallSpacings;
  const Vec3f& w = t.thickness->where;
  // What count would resolve it (the count goes as 1/d³), and what to change: the count's budget when that held it back.
  const double count = s.sizing.count > 0.0 ? s.sizing.count : double(s.sampling.auto_count);
  const double would = count * std::pow(d / need, 3.0);
  const std::string knob =
      !s.auto_radius                    ? std::string(" (solver.particle_radius)")
      : s.sizing.limited_by == "skinned"
          ? fmt::format(", about {:.3g} particles (sampling.auto_count: a scene with a skinned target "
                        "keeps it unless the scene names a count)", would)
      : s.sizing.limited_by == "memory" ? fmt::format(", about {:.3g} particles, more than the memory limit allows "
                                                      "(limits.max_memory_mb)", would)
      : s.auto_resolution               ? fmt::format(", about {:.3g} particles, over the budget of {} (sampling.max_auto_count)",
                                                      would, s.sampling.max_auto_count)
                                        : fmt::format(", about {:.3g} particles (sampling.auto_count)", would);
  return fmt::format("target {}: walls {:.3g} m thin near ({:.3g}, {:.3g}, {:.3g}) are {:.1f} spacings across (d = {:.3g} m) "
                     "and may come out with holes: {:g} spacings need d <= {:.3g} m{}",
                     k, t.thickness->thinnest, w.x(), w.y(), w.z(), t.thickness->thinnest / d, d, kWallSpacings, need, knob);
}

void assign_targets(sim::ParticleSet& p, const std::vector<TargetGeometry>& targets) {
  const std::size_t n = p.size();
  std::fill(p.target.begin(), p.target.end(), sim::kFreeFluid);
  if (targets.empty() || n == 0) return;
  if (targets.size() == 1) {
    std::fill(p.target.begin(), p.target.end(), std::uint8_t{0});
    return;
  }
  double total = 0.0;
  for (const auto& t : targets) total += std::max(t.volume, 1e-30);
  std::vector<std::size_t> order(targets.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return targets[a].volume > targets[b].volume; });
  std::vector<Index> free_idx(n);
  std::iota(free_idx.begin(), free_idx.end(), Index{0});
  std::size_t given = 0;
  for (std::size_t k = 0; k < order.size(); ++k) {
    const std::size_t t = order[k];
    const std::size_t want =
        k + 1 == order.size() ? n - given
                              : std::min(n - given, static_cast<std::size_t>(std::llround(double(n) * std::max(targets[t].volume, 1e-30) / total)));
    const Vec3f c = 0.5f * (targets[t].box.min + targets[t].box.max);
    // Nearest `want` of the free particles (ties by id, so the split is deterministic).
    auto closer = [&](Index a, Index b) {
      const float da = (p.position[a] - c).squaredNorm(), db = (p.position[b] - c).squaredNorm();
      return da < db || (da == db && p.id[a] < p.id[b]);
    };
    std::nth_element(free_idx.begin(), free_idx.begin() + static_cast<std::ptrdiff_t>(want), free_idx.end(), closer);
    for (std::size_t q = 0; q < want; ++q) p.target[free_idx[q]] = static_cast<std::uint8_t>(t);
    free_idx.erase(free_idx.begin(), free_idx.begin() + static_cast<std::ptrdiff_t>(want));
    given += want;
  }
}

}  // namespace ff::pipeline
