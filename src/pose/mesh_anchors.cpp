#include "pose/mesh_anchors.h"

#include "pose/cage_guard.h"
#include "core/parallel.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace ff::pose {

bool MeshAnchors::consistent(std::size_t samples) const {
  const std::size_t nv = mesh.vertices.size();
  if (caged()) {
    if (cage.size() != samples * nv || !triangle.empty() || vertex_joints.size() != nv || vertex_weights.size() != nv)
      return false;
    if (!guarded()) return true;
    const std::size_t nt = mesh.triangles.size();
    if (guard_begin.size() != samples + 1 || guard_depth.size() != samples || guard_begin.back() != guard_triangle.size() ||
        orientation.size() != nt || across.size() != nt || corner_begin.size() != nv + 1 ||
        corner_begin.back() != corner_triangle.size())
      return false;
    for (std::size_t i = 0; i < samples; ++i)
      if (guard_begin[i] > guard_begin[i + 1] || !(guard_depth[i] >= 0.0f) || !std::isfinite(guard_depth[i])) return false;
    for (std::size_t v = 0; v < nv; ++v)
      if (corner_begin[v] > corner_begin[v + 1]) return false;
    for (const Index t : guard_triangle)
      if (t >= nt) return false;
    for (const Index t : corner_triangle)
      if (t >= nt) return false;
    for (std::size_t t = 0; t < nt; ++t) {
      if (orientation[t] < -1 || orientation[t] > 1) return false;
      for (const Index o : across[t])
        if (o != kInvalidIndex && o >= nt) return false;
    }
    if (!fold_partner.empty()) {
      if (fold_partner.size() != samples) return false;
      for (std::size_t i = 0; i < samples; ++i)  // a partner is a sample with no partner of its own
        if (const Index j = fold_partner[i]; j != kInvalidIndex && (j >= samples || fold_partner[j] != kInvalidIndex)) return false;
    }
    for (const auto& tri : mesh.triangles)
      for (const Index v : tri)
        if (v >= nv) return false;
    return true;
  }
  if (triangle.size() != samples || bary.size() != samples || height.size() != samples || vertex_joints.size() != nv ||
      vertex_weights.size() != nv)
    return false;
  for (const Index t : triangle)
    if (t >= mesh.triangles.size()) return false;
  for (const auto& tri : mesh.triangles)
    for (const Index v : tri)
      if (v >= nv) return false;
  return true;
}

void MeshAnchors::pose_vertices(const PosedJoints& joints, std::vector<Vec3f>& out) const {
  out.resize(mesh.vertices.size());
  for (std::size_t v = 0; v < out.size(); ++v) out[v] = joints.apply(vertex_joints[v], vertex_weights[v], mesh.vertices[v]);
}

Vec3f MeshAnchors::place(std::size_t i, const std::vector<Vec3f>& posed, bool folds) const {
  if (caged()) {
    const float* w = cage.data() + i * posed.size();
    Vec3f x = Vec3f::Zero();
    for (std::size_t v = 0; v < posed.size(); ++v) x += w[v] * posed[v];
    return guarded() ? keep_inside(*this, i, x, posed, folds) : x;
  }
  const auto& tri = mesh.triangles[triangle[i]];
  const Vec3f &a = posed[tri[0]], &b = posed[tri[1]], &c = posed[tri[2]];
  const auto& w = bary[i];
  Vec3f x = w[0] * a + w[1] * b + w[2] * c;
  if (height[i] != 0.0f) {
    const Vec3f n = (b - a).cross(c - a);
    const float len = n.norm();
    if (len > 0.0f) x += (height[i] / len) * n;
  }
  return x;
}

Result<MeshAnchors> anchor_to_cage(io::TriangleMesh mesh,
                                   std::vector<std::array<std::uint16_t, io::kMaxInfluences>> vertex_joints,
                                   std::vector<std::array<float, io::kMaxInfluences>> vertex_weights,
                                   const std::vector<Vec3f>& samples, std::size_t max_weights) {
  MeshAnchors a;
  a.mesh = std::move(mesh), a.vertex_joints = std::move(vertex_joints), a.vertex_weights = std::move(vertex_weights);
  const std::size_t nv = a.mesh.vertices.size();
  if (nv == 0 || a.mesh.triangles.empty()) return param_error("a cage needs a mesh with triangles");
  // Sized before it is allocated (issue 20): one float per sample and vertex.
  if (samples.size() > max_weights / nv)
    return param_error(fmt::format("{} control samples in a cage of {} vertices would take {:.0f} MiB of weights, more "
                                   "than {:.0f} MiB; use \"follow\": \"weights\" in the target's animation",
                                   samples.size(), nv, 4.0 * double(samples.size()) * double(nv) / 1048576.0,
                                   4.0 * double(max_weights) / 1048576.0));
  a.cage.resize(samples.size() * nv);
  core::parallel_for(static_cast<std::int64_t>(samples.size()), [&](std::int64_t i) {
    mean_value_coordinates(a.mesh, samples[static_cast<std::size_t>(i)], a.cage.data() + static_cast<std::size_t>(i) * nv);
  });
  if (!a.consistent(samples.size())) return param_error("a cage's skin weights do not match its vertices");
  return a;
}

// Ju, Schaefer & Warren (2005), "Mean value coordinates for closed triangular meshes", in double: per triangle, the
// angles θ_i its edges subtend from x on the unit sphere, and its share of each corner's weight; a point in a
// triangle's plane but outside it takes nothing from that triangle.
void mean_value_coordinates(const io::TriangleMesh& mesh, const Vec3f& xf, float* out) {
  using V = Eigen::Vector3d;
  const std::size_t nv = mesh.vertices.size();
  const V x = xf.cast<double>();
  std::vector<double> d(nv), w(nv, 0.0);
  std::vector<V> u(nv);
  for (std::size_t v = 0; v < nv; ++v) {
    const V p = mesh.vertices[v].cast<double>() - x;
    d[v] = p.norm();
    if (d[v] < 1e-9) {  // on a vertex
      std::fill(out, out + nv, 0.0f);
      out[v] = 1.0f;
      return;
    }
    u[v] = p / d[v];
  }
  constexpr double kPi = 3.14159265358979323846;
  for (const auto& t : mesh.triangles) {
    double theta[3], c[3], s[3];
    for (int i = 0; i < 3; ++i) {
      const double l = (u[t[(i + 1) % 3]] - u[t[(i + 2) % 3]]).norm();
      theta[i] = 2.0 * std::asin(std::min(1.0, 0.5 * l));
    }
    const double h = 0.5 * (theta[0] + theta[1] + theta[2]);
    if (kPi - h < 1e-9) {  // x on the triangle: its barycentrics
      std::fill(out, out + nv, 0.0f);
      double sum = 0.0, b[3];
      for (int i = 0; i < 3; ++i) sum += b[i] = std::sin(theta[i]) * d[t[(i + 2) % 3]] * d[t[(i + 1) % 3]];
      for (int i = 0; i < 3; ++i) out[t[i]] += static_cast<float>(b[i] / sum);
      return;
    }
    const double sign = u[t[0]].dot(u[t[1]].cross(u[t[2]])) < 0.0 ? -1.0 : 1.0;
    bool degenerate = false;
    for (int i = 0; i < 3; ++i) {
      c[i] = 2.0 * std::sin(h) * std::sin(h - theta[i]) / (std::sin(theta[(i + 1) % 3]) * std::sin(theta[(i + 2) % 3])) - 1.0;
      s[i] = sign * std::sqrt(std::max(0.0, 1.0 - c[i] * c[i]));
      degenerate = degenerate || std::abs(s[i]) < 1e-9;
    }
    if (degenerate) continue;
    for (int i = 0; i < 3; ++i) {
      const int a = (i + 1) % 3, b = (i + 2) % 3;
      w[t[i]] += (theta[i] - c[a] * theta[b] - c[b] * theta[a]) / (d[t[i]] * std::sin(theta[a]) * s[b]);
    }
  }
  double sum = 0.0;
  for (double v : w) sum += v;
  if (!(std::abs(sum) > 0.0) || !std::isfinite(sum)) {  // cannot happen for a closed mesh; the nearest vertex then
    std::size_t best = 0;
    for (std::size_t v = 1; v < nv; ++v) best = d[v] < d[best] ? v : best;
    std::fill(out, out + nv, 0.0f);
    out[best] = 1.0f;
    return;
  }
  for (std::size_t v = 0; v < nv; ++v) out[v] = static_cast<float>(w[v] / sum);
}

void triangle_anchor(const Vec3f& p, const Vec3f& a, const Vec3f& b, const Vec3f& c, std::array<float, 3>& bary,
                     float& height) {
  const Vec3f e1 = b - a, e2 = c - a, n = e1.cross(e2);
  const float len2 = n.squaredNorm();
  height = 0.0f;
  if (!(len2 > 0.0f) || !std::isfinite(len2)) {  // degenerate: the nearest corner whole
    const float da = (p - a).squaredNorm(), db = (p - b).squaredNorm(), dc = (p - c).squaredNorm();
    bary = da <= db && da <= dc ? std::array<float, 3>{1, 0, 0}
           : db <= dc           ? std::array<float, 3>{0, 1, 0}
                                : std::array<float, 3>{0, 0, 1};
    return;
  }
  // p − a = u e1 + v e2 + h n̂: the in-plane part solved by Cramer's rule on the normal's components.
  const Vec3f q = p - a;
  const float u = q.cross(e2).dot(n) / len2, v = e1.cross(q).dot(n) / len2;
  bary = {1.0f - u - v, u, v};
  height = q.dot(n) / std::sqrt(len2);
}

}  // namespace ff::pose
