#include "pipeline/liquid_look.h"

#include "core/neighbor_grid.h"
#include "core/parallel.h"
#include "core/point_tree.h"
#include "pose/skinned_target.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <numeric>
#include <random>
#include <unordered_map>

namespace ff::pipeline {
namespace fs = std::filesystem;

namespace {

// Per look vertex, the vertex of `mesh` at the same position (bit for bit: both come from the same file through the
// same transform); a look vertex with no twin (Assimp joined differently) takes the nearest one.
std::vector<Index> twin_vertices(const io::TriangleMesh& look, const io::TriangleMesh& mesh) {
  const auto key = [](const Vec3f& v) {
    std::uint32_t b[3];
    std::memcpy(b, v.data(), sizeof b);
    return (std::uint64_t(b[0]) * 0x9E3779B97F4A7C15ull) ^ (std::uint64_t(b[1]) * 0xC2B2AE3D27D4EB4Full) ^ b[2];
  };
  std::unordered_multimap<std::uint64_t, Index> at;
  at.reserve(mesh.vertices.size());
  for (Index v = 0; v < mesh.vertices.size(); ++v) at.emplace(key(mesh.vertices[v]), v);
  std::vector<Index> twin(look.vertices.size(), kInvalidIndex);
  std::optional<core::PointTree> tree;
  for (std::size_t i = 0; i < twin.size(); ++i) {
    const auto [a, b] = at.equal_range(key(look.vertices[i]));
    for (auto it = a; it != b; ++it)
      if (mesh.vertices[it->second] == look.vertices[i]) twin[i] = it->second;
    if (twin[i] != kInvalidIndex) continue;
    if (!tree) tree.emplace(mesh.vertices);
    const auto n = tree->nearest(look.vertices[i]);
    twin[i] = tree->original(n.slot);
  }
  return twin;
}

// The look of one mesh of target t (its first mesh, or a morph's), with its closest-point field; nullopt (and a
// warning) when it cannot be read.
std::optional<LiquidLooks::Phase> load_phase(const scene::TargetSpec& spec, std::size_t t, const fs::path& mesh,
                                             double from, LiquidLooks& out) {
  auto look = io::load_target_look(mesh, spec.transform);
  if (!look) {
    out.warnings.push_back(fmt::format("target {}: its look cannot be read ({}): its liquid takes its tint", t,
                                       look.error().message));
    return std::nullopt;
  }
  for (const std::string& w : look->warnings) out.warnings.push_back(fmt::format("target {}: {}", t, w));
  auto field = sampling::MeshField::build(look->mesh);
  if (!field) {
    out.warnings.push_back(fmt::format("target {}: its look has no surface ({}): its liquid takes its tint", t,
                                       field.error().message));
    return std::nullopt;
  }
  LiquidLooks::Phase p;
  p.from = from;
  p.look = std::move(*look);
  p.field = std::move(*field);
  return p;
}

// Barycentric coordinates of p (on or near triangle abc) in it, clamped to the triangle.
Vec3f barycentric(const Vec3f& p, const Vec3f& a, const Vec3f& b, const Vec3f& c) {
  const Vec3f e0 = b - a, e1 = c - a, w = p - a;
  const double d00 = e0.dot(e0), d01 = e0.dot(e1), d11 = e1.dot(e1), d20 = w.dot(e0), d21 = w.dot(e1);
  const double den = d00 * d11 - d01 * d01;
  if (!(std::abs(den) > 0.0)) return Vec3f(1.0f, 0.0f, 0.0f);
  double v = (d11 * d20 - d01 * d21) / den, u = (d00 * d21 - d01 * d20) / den;
  v = std::clamp(v, 0.0, 1.0), u = std::clamp(u, 0.0, 1.0);
  if (u + v > 1.0) {
    const double s = u + v;
    u /= s, v /= s;
  }
  return Vec3f(float(1.0 - u - v), float(v), float(u));
}

// Target t's phase at `time` and the field to ask there (the rest field, or the skinned look posed at that time).
// No pointer into itself (it is moved into a vector): field() picks the posed field or the phase's.
struct PosedLook {
  const LiquidLooks::Phase* phase = nullptr;
  std::optional<sampling::MeshField> posed;  // a skinned phase's moved field
  std::vector<Vec3f> vertices;               // ... and its look's vertices posed (empty: the look's own)
  Eigen::Affine3f rest = Eigen::Affine3f::Identity();
  const sampling::MeshField* field() const {
    return posed ? &*posed : phase != nullptr ? &*phase->field : nullptr;
  }
};

PosedLook pose_look(const LiquidLooks::Target& t, double time) {
  PosedLook out;
  if (t.phases.empty()) return out;
  std::size_t k = 0;
  while (k + 1 < t.phases.size() && time >= t.phases[k + 1].from) ++k;
  out.phase = &t.phases[k];
  if (t.motion.moving()) out.rest = t.motion.at(time).rest_from_world();
  if (k == 0 && t.skin && t.skin_mesh != nullptr && !out.phase->skin_vertex.empty()) {
    const pose::PosedJoints joints = pose::joints_at(*t.skin, time, t.skin->spec.skinning);
    const auto& sv = out.phase->skin_vertex;
    std::vector<Vec3f> x(sv.size());
    for (std::size_t i = 0; i < x.size(); ++i)
      x[i] = joints.apply(t.skin->skin.joints[sv[i]], t.skin->skin.weights[sv[i]], t.skin_mesh->vertices[sv[i]]);
    auto moved = out.phase->field->moved(x, false);
    if (moved) out.posed = std::move(*moved), out.vertices = std::move(x);
  }
  return out;
}

// The colour of the look's surface nearest to q (the vertex in the target's rest frame), and its distance.
Vec3f look_colour(const PosedLook& p, const Vec3f& q, float* distance = nullptr) {
  const auto c = p.field()->closest(q);
  if (distance != nullptr) *distance = c.distance;
  const auto& tri = p.phase->look.mesh.triangles[c.triangle];
  const std::vector<Vec3f>& x = p.vertices.empty() ? p.phase->look.mesh.vertices : p.vertices;
  return p.phase->look.colour_at(c.triangle, barycentric(c.point, x[tri[0]], x[tri[1]], x[tri[2]]));
}

// The one texture target t's whole look is (one mesh, UVs, no vertex colours, every triangle the same texture and
// factor), or null.
std::shared_ptr<const io::MeshTexture> single_texture(const LiquidLooks::Target& t) {
  if (t.appearance != scene::Appearance::Target || t.phases.size() != 1) return nullptr;
  const io::TargetLook& look = t.phases[0].look;
  if (look.uv.empty() || !look.colours.empty() || look.material.empty()) return nullptr;
  const io::LookMaterial& first = look.materials[look.material[0]];
  if (first.texture < 0) return nullptr;
  const auto factor = [](const io::LookMaterial& m) { return m.factor_with_texture ? m.colour : Vec3f::Ones(); };
  for (const auto m : look.material) {
    const io::LookMaterial& other = look.materials[m];
    if (other.texture != first.texture || factor(other) != factor(first)) return nullptr;
  }
  auto out = std::make_shared<io::MeshTexture>();
  out->image = look.textures[std::size_t(first.texture)];
  out->factor = factor(first);
  return out;
}

// Barycentric coordinates of p's projection on the plane of abc, not clamped (outside the triangle too): the
// triangle's UV map extended over its plane.
Vec3f plane_barycentric(const Vec3f& p, const Vec3f& a, const Vec3f& b, const Vec3f& c) {
  const Vec3f n = (b - a).cross(c - a);
  const float area = n.squaredNorm();
  if (!(area > 0.0f)) return Vec3f(1.0f, 0.0f, 0.0f);
  const float wa = n.dot((b - p).cross(c - p)) / area, wb = n.dot((c - p).cross(a - p)) / area;
  return Vec3f(wa, wb, 1.0f - wa - wb);
}

float srgb_step(float linear) { return float(io::linear_to_srgb(linear)); }
double srgb_difference(const Vec3f& a, const Vec3f& b) {
  double d = 0.0;
  for (int c = 0; c < 3; ++c) d += std::abs(srgb_step(a[c]) - srgb_step(b[c]));
  return d / 3.0;
}

}  // namespace

bool LiquidLooks::coloured() const {
  for (const Target& t : targets)
    if (t.appearance != scene::Appearance::Water) return true;
  return false;
}

std::vector<io::WaterMaterial> LiquidLooks::materials() const {
  std::vector<io::WaterMaterial> out;
  for (const Target& t : targets) {
    io::WaterMaterial w;
    w.tint = t.tint;
    w.coloured = t.appearance != scene::Appearance::Water;
    out.push_back(w);
  }
  return out;
}

LiquidLooks load_liquid_looks(const scene::Scene& scene, const std::vector<TargetGeometry>& geometry,
                              const std::vector<pose::TargetMotion>& motions) {
  LiquidLooks out;
  for (std::size_t t = 0; t < scene.targets.size(); ++t) {
    const scene::TargetSpec& spec = scene.targets[t];
    LiquidLooks::Target& target = out.targets.emplace_back();
    target.appearance = spec.appearance;
    target.tint = spec.tint;
    if (t < motions.size()) target.motion = motions[t];
    if (spec.appearance != scene::Appearance::Target) continue;
    if (t < geometry.size() && geometry[t].skin) target.skin = geometry[t].skin, target.skin_mesh = &geometry[t].mesh;
    auto first = load_phase(spec, t, spec.mesh, -std::numeric_limits<double>::infinity(), out);
    if (!first) {
      target.appearance = scene::Appearance::Tint;
      continue;
    }
    if (target.skin) first->skin_vertex = twin_vertices(first->look.mesh, *target.skin_mesh);
    target.phases.push_back(std::move(*first));
    for (const auto& swap : spec.swaps)
      if (auto p = load_phase(spec, t, swap.mesh, swap.time, out)) target.phases.push_back(std::move(*p));
  }
  if (out.targets.size() == 1) out.targets[0].texture = single_texture(out.targets[0]);
  for (const std::string& w : out.warnings) spdlog::warn("look: {}", w);
  return out;
}

std::vector<std::uint8_t> vertex_targets(const io::TriangleMesh& mesh, std::span<const Vec3f> particles,
                                         std::span<const std::uint8_t> targets, float d, std::size_t count) {
  std::vector<std::uint8_t> out(mesh.vertices.size(), 255);
  if (targets.size() != particles.size() || mesh.vertices.empty() || particles.empty()) return out;
  const float r = 2.0f * d;
  core::NeighborGrid grid(r);
  grid.build(particles);
  core::NeighborList nl;
  grid.query(particles, mesh.vertices, r, nl);
  for (std::size_t v = 0; v < mesh.vertices.size(); ++v) {
    float best = INFINITY;
    for (Index j : nl.of(v)) {
      if (targets[j] >= count) continue;
      const float d2 = (particles[j] - mesh.vertices[v]).squaredNorm();
      if (d2 < best) best = d2, out[v] = targets[j];
    }
  }
  return out;
}

std::vector<Vec3f> liquid_colours(const LiquidLooks& looks, const io::TriangleMesh& mesh,
                                  std::span<const std::uint8_t> vertex_target, double time) {
  std::vector<Vec3f> out(mesh.vertices.size(), Vec3f::Ones());
  const std::size_t n = looks.targets.size();
  if (n == 0) return out;
  std::vector<PosedLook> posed;
  posed.reserve(n);
  for (const auto& t : looks.targets) posed.push_back(pose_look(t, time));
  const auto colour_of = [&](std::size_t t, const Vec3f& p) -> Vec3f {
    const LiquidLooks::Target& target = looks.targets[t];
    if (target.appearance == scene::Appearance::Water) return Vec3f::Ones();
    if (target.appearance == scene::Appearance::Tint || posed[t].field() == nullptr) return target.tint;
    return look_colour(posed[t], posed[t].rest * p);
  };
  core::parallel_for(static_cast<std::int64_t>(out.size()), [&](std::int64_t i) {
    const auto v = static_cast<std::size_t>(i);
    const Vec3f& p = mesh.vertices[v];
    std::size_t t = vertex_target.size() != out.size() ? 0 : vertex_target[v];
    if (t < n) {
      out[v] = colour_of(t, p);
      return;
    }
    // Free fluid: the target whose look's surface is nearest; targets without a look (water, tint) only when no
    // target has one.
    float best = std::numeric_limits<float>::infinity();
    out[v] = colour_of(0, p);
    for (std::size_t k = 0; k < n; ++k) {
      if (posed[k].field() == nullptr || looks.targets[k].appearance != scene::Appearance::Target) continue;
      float dist = 0.0f;
      const Vec3f c = look_colour(posed[k], posed[k].rest * p, &dist);
      if (dist < best) best = dist, out[v] = c;
    }
  });
  return out;
}

std::vector<std::array<io::Vec2f, 3>> liquid_uvs(const LiquidLooks& looks, const io::TriangleMesh& mesh, double time) {
  if (looks.targets.size() != 1 || looks.targets[0].texture == nullptr || mesh.triangles.empty()) return {};
  const PosedLook p = pose_look(looks.targets[0], time);
  if (p.field() == nullptr) return {};
  const io::TargetLook& look = p.phase->look;
  const std::vector<Vec3f>& x = p.vertices.empty() ? look.mesh.vertices : p.vertices;
  const auto uv_at = [&](Index t, const Vec3f& w) {
    const auto& tri = look.mesh.triangles[t];
    return io::Vec2f(w.x() * look.uv[tri[0]] + w.y() * look.uv[tri[1]] + w.z() * look.uv[tri[2]]);
  };
  // Per vertex: the UV of its nearest target point (in the target's rest frame, posed as the colours are).
  std::vector<Vec3f> q(mesh.vertices.size());
  std::vector<io::Vec2f> at(mesh.vertices.size());
  std::vector<Index> on(mesh.vertices.size());  // the target triangle of that point
  core::parallel_for(static_cast<std::int64_t>(q.size()), [&](std::int64_t i) {
    const auto v = static_cast<std::size_t>(i);
    q[v] = p.rest * mesh.vertices[v];
    const auto c = p.field()->closest(q[v]);
    const auto& tri = look.mesh.triangles[c.triangle];
    at[v] = uv_at(c.triangle, barycentric(c.point, x[tri[0]], x[tri[1]], x[tri[2]]));
    on[v] = c.triangle;
  });
  // Per triangle: its corners' UVs, unless they disagree with the UV map of the target triangle nearest to its centre
  // (extended over its plane) by more than half the triangle's size in that map, plus two texels: a seam between
  // them, or the wrap of a map around a cylinder. A triangle whose corners agree with the map of its first corner's
  // triangle is inside one chart, and skips the search for its centre's (most triangles: it is the costly part).
  const io::Texture& image = looks.targets[0].texture->image;
  const float texel = 1.0f / float(std::max(image.width, image.height));
  const auto mapped_by = [&](Index near, const std::array<Index, 3>& f, std::array<io::Vec2f, 3>& mapped) {
    const auto& lt = look.mesh.triangles[near];
    for (std::size_t k = 0; k < 3; ++k) mapped[k] = uv_at(near, plane_barycentric(q[f[k]], x[lt[0]], x[lt[1]], x[lt[2]]));
    float size = 0.0f;
    for (std::size_t k = 0; k < 3; ++k) size = std::max(size, (mapped[k] - mapped[(k + 1) % 3]).norm());
    const float tolerance = 0.5f * size + 2.0f * texel;
    bool agree = true;
    for (std::size_t k = 0; k < 3; ++k) agree &= (mapped[k] - at[f[k]]).norm() <= tolerance;
    return agree;
  };
  std::vector<std::array<io::Vec2f, 3>> out(mesh.triangles.size());
  core::parallel_for(static_cast<std::int64_t>(out.size()), [&](std::int64_t i) {
    const auto t = static_cast<std::size_t>(i);
    const auto& f = mesh.triangles[t];
    std::array<io::Vec2f, 3> mapped;
    const auto centre = [&] { return p.field()->closest((q[f[0]] + q[f[1]] + q[f[2]]) / 3.0f).triangle; };
    const bool agree = mapped_by(on[f[0]], f, mapped) || mapped_by(centre(), f, mapped);
    out[t] = agree ? std::array<io::Vec2f, 3>{at[f[0]], at[f[1]], at[f[2]]} : mapped;
  });
  return out;
}

LookMeasure measure_look(const LiquidLooks& looks, const io::TriangleMesh& mesh, double time, std::size_t points) {
  LookMeasure m;
  if (looks.targets.size() != 1 || mesh.triangles.empty() || mesh.colours.size() != mesh.vertices.size() ||
      mesh.corner_uv.size() != mesh.triangles.size() || mesh.texture == nullptr)
    return m;
  const PosedLook p = pose_look(looks.targets[0], time);
  if (p.field() == nullptr) return m;
  // Points uniform in area over the triangles, from a fixed seed (the same figures every time).
  std::vector<double> cum(mesh.triangles.size());
  double total = 0.0;
  for (std::size_t t = 0; t < cum.size(); ++t) {
    const auto& f = mesh.triangles[t];
    total += 0.5 * double((mesh.vertices[f[1]] - mesh.vertices[f[0]]).cross(mesh.vertices[f[2]] - mesh.vertices[f[0]]).norm());
    cum[t] = total;
  }
  if (!(total > 0.0)) return m;
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  struct Sample {
    std::size_t t;
    Vec3f w;
  };
  std::vector<Sample> samples(points);
  for (Sample& s : samples) {
    s.t = std::min<std::size_t>(std::size_t(std::lower_bound(cum.begin(), cum.end(), u01(rng) * total) - cum.begin()), cum.size() - 1);
    const double r1 = std::sqrt(u01(rng)), r2 = u01(rng);
    s.w = Vec3f(float(1.0 - r1), float(r1 * (1.0 - r2)), float(r1 * r2));
  }
  std::vector<double> by_vertex(points), by_uv(points);
  const io::MeshTexture& tex = *mesh.texture;
  core::parallel_for(static_cast<std::int64_t>(points), [&](std::int64_t i) {
    const Sample& s = samples[std::size_t(i)];
    const auto& f = mesh.triangles[s.t];
    const Vec3f at = s.w.x() * mesh.vertices[f[0]] + s.w.y() * mesh.vertices[f[1]] + s.w.z() * mesh.vertices[f[2]];
    const Vec3f truth = look_colour(p, p.rest * at);
    const Vec3f vc = s.w.x() * mesh.colours[f[0]] + s.w.y() * mesh.colours[f[1]] + s.w.z() * mesh.colours[f[2]];
    const auto& uv = mesh.corner_uv[s.t];
    const Vec3f tc = io::sample_texture(tex.image, s.w.x() * uv[0] + s.w.y() * uv[1] + s.w.z() * uv[2]).cwiseProduct(tex.factor);
    by_vertex[std::size_t(i)] = srgb_difference(vc, truth);
    by_uv[std::size_t(i)] = srgb_difference(tc, truth);
  });
  m.points = points;
  m.vertex_colours = std::accumulate(by_vertex.begin(), by_vertex.end(), 0.0) / double(points);
  m.uvs = std::accumulate(by_uv.begin(), by_uv.end(), 0.0) / double(points);
  return m;
}

}  // namespace ff::pipeline
