// Skin weights and bind pose for the formed mesh (pose/skin_transfer.h).
#include "pose/skin_transfer.h"
#include "pose/skin_eval.h"

#include "core/parallel.h"
#include "sampling/mesh_field.h"

#include <Eigen/Dense>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace ff::pose {
namespace {

using Mat4d = Eigen::Matrix4d;
using Mat3d = Eigen::Matrix3d;

/// The relative determinant below which a blended matrix counts as singular (see the header).
constexpr double kSingularDet = 1e-2;
/// Formed vertices per warm-started run of closest-point queries (fixed: the result never depends on threads).
constexpr std::int64_t kBlock = 256;

/// Barycentric coordinates of `p` (a point on or near triangle a b c), clamped to the triangle and summing to 1.
Vec3d barycentric(const Vec3f& p, const Vec3f& a, const Vec3f& b, const Vec3f& c) {
  const Vec3d v0 = (b - a).cast<double>(), v1 = (c - a).cast<double>(), v2 = (p - a).cast<double>();
  const double d00 = v0.dot(v0), d01 = v0.dot(v1), d11 = v1.dot(v1), d20 = v2.dot(v0), d21 = v2.dot(v1);
  const double den = d00 * d11 - d01 * d01;
  if (!(den > 0.0)) return {1.0, 0.0, 0.0};
  double v = (d11 * d20 - d01 * d21) / den, w = (d00 * d21 - d01 * d20) / den;
  Vec3d l(1.0 - v - w, v, w);
  l = l.cwiseMax(0.0);
  const double s = l.sum();
  return s > 0.0 ? Vec3d(l / s) : Vec3d(1.0, 0.0, 0.0);
}

struct Influences {
  std::array<std::uint16_t, io::kMaxInfluences> joints{};
  std::array<float, io::kMaxInfluences> weights{};
};

/// Σ_k λ_k · (corner k's weights), equal joints merged, the four largest kept (ties: lower joint), renormalised.
/// Empty weights (all zero) when the corners have none.
Influences interpolate(const io::Skin& skin, const std::array<Index, 3>& tri, const Vec3d& l) {
  std::array<std::pair<std::uint16_t, double>, 3 * io::kMaxInfluences> acc{};
  int n = 0;
  for (int k = 0; k < 3; ++k) {
    if (l[k] <= 0.0) continue;
    const auto& j = skin.joints[tri[static_cast<std::size_t>(k)]];
    const auto& w = skin.weights[tri[static_cast<std::size_t>(k)]];
    for (int s = 0; s < io::kMaxInfluences; ++s) {
      if (!(w[s] > 0.0f)) continue;
      int at = 0;
      while (at < n && acc[static_cast<std::size_t>(at)].first != j[s]) ++at;
      if (at == n) acc[static_cast<std::size_t>(n++)] = {j[s], 0.0};
      acc[static_cast<std::size_t>(at)].second += l[k] * double(w[s]);
    }
  }
  std::sort(acc.begin(), acc.begin() + n, [](const auto& x, const auto& y) {
    return x.second != y.second ? x.second > y.second : x.first < y.first;
  });
  Influences out;
  const int keep = std::min(n, io::kMaxInfluences);
  double sum = 0.0;
  for (int k = 0; k < keep; ++k) sum += acc[static_cast<std::size_t>(k)].second;
  if (!(sum > 0.0)) return out;
  for (int k = 0; k < keep; ++k) {
    out.joints[static_cast<std::size_t>(k)] = acc[static_cast<std::size_t>(k)].first;
    out.weights[static_cast<std::size_t>(k)] = static_cast<float>(acc[static_cast<std::size_t>(k)].second / sum);
  }
  return out;
}

/// The joint with the largest weight of vertex `v` (ties: the first slot).
std::uint16_t dominant_joint(const io::Skin& skin, Index v) {
  const auto& w = skin.weights[v];
  int best = 0;
  for (int s = 1; s < io::kMaxInfluences; ++s)
    if (w[s] > w[best]) best = s;
  return skin.joints[v][best];
}

}  // namespace

std::vector<io::Mat4f> world_joint_matrices(const io::Skin& skin, const io::MeshTransform& transform, int clip, double t) {
  std::vector<io::Mat4f> k;
  joint_matrices(skin, clip, t, k);
  const Mat4d tm = io::transform_matrix(transform).cast<double>();
  const Mat4d ti = tm.inverse();
  for (auto& m : k) m = (tm * m.cast<double>() * ti).cast<float>();
  return k;
}

namespace {

// The inputs transfer_skin takes: a formed mesh, a target with triangles and a weight per vertex, a finite time.
Status check_transfer_input(const io::TriangleMesh& formed, const io::TriangleMesh& target_bind, const io::Skin& skin,
                            double t) {
  const std::size_t nt = target_bind.vertices.size();
  if (formed.vertices.empty()) return input_error("skin transfer: the formed mesh is empty");
  if (target_bind.triangles.empty()) return input_error("skin transfer: the target mesh has no triangles");
  if (skin.joints.size() != nt || skin.weights.size() != nt)
    return input_error(fmt::format("skin transfer: the skin has weights for {} vertices, the target has {}",
                                   std::min(skin.joints.size(), skin.weights.size()), nt));
  if (!std::isfinite(t)) return input_error("skin transfer: the time is not finite");
  for (const auto& v : formed.vertices)
    if (!v.allFinite()) return input_error("skin transfer: the formed mesh has a non-finite vertex");
  return {};
}

// Every weighted influence of the target names one of the `joints` joints.
Status check_joint_refs(const io::Skin& skin, std::size_t joints) {
  for (std::size_t v = 0; v < skin.joints.size(); ++v)
    for (int s = 0; s < io::kMaxInfluences; ++s)
      if (skin.weights[v][s] != 0.0f && skin.joints[v][s] >= joints)
        return input_error(fmt::format("skin transfer: target vertex {} refers to joint {} of {}", v, skin.joints[v][s],
                                       joints));
  return {};
}

// The joint matrices in double, with their linear parts' |determinant| and inverse.
struct JointTerms {
  std::vector<Mat4d> kd;
  std::vector<double> kdet;
  std::vector<Mat3d> kinv;
};

JointTerms joint_terms(const std::vector<io::Mat4f>& kw) {
  JointTerms j;
  j.kd.resize(kw.size()), j.kdet.resize(kw.size()), j.kinv.resize(kw.size());
  for (std::size_t k = 0; k < kw.size(); ++k) {
    j.kd[k] = kw[k].cast<double>();
    j.kdet[k] = std::abs(j.kd[k].topLeftCorner<3, 3>().determinant());
    j.kinv[k] = j.kd[k].topLeftCorner<3, 3>().inverse();
  }
  return j;
}

}  // namespace

Result<SkinnedSurface> transfer_skin(const io::TriangleMesh& formed, const io::TriangleMesh& target_bind,
                                     const io::Skin& skin, const io::MeshTransform& transform, int clip, double t) {
  const std::size_t nt = target_bind.vertices.size();
  FF_CHECK(check_transfer_input(formed, target_bind, skin, t));
  const std::vector<io::Mat4f> kw = world_joint_matrices(skin, transform, clip, t);
  FF_CHECK(check_joint_refs(skin, kw.size()));

  // The target posed at (clip, t), and its closest-point index.
  io::TriangleMesh posed;
  posed.triangles = target_bind.triangles;
  posed.vertices.resize(nt);
  core::parallel_for(static_cast<std::int64_t>(nt), [&](std::int64_t i) {
    const auto v = static_cast<std::size_t>(i);
    posed.vertices[v] = io::skin_point(kw, skin.joints[v], skin.weights[v], target_bind.vertices[v]);
  });
  auto field = sampling::MeshField::build(posed);
  if (!field) return input_error("skin transfer: the posed target: " + field.error().message);
  const JointTerms jt = joint_terms(kw);

  const std::size_t nf = formed.vertices.size();
  SkinnedSurface out;
  out.bind_mesh.triangles = formed.triangles;
  out.bind_mesh.vertices.resize(nf);
  out.joints.resize(nf);
  out.weights.resize(nf);
  std::vector<std::uint8_t> fell_back(nf, 0);
  std::vector<float> miss(nf, 0.0f), dist(nf, 0.0f);
  core::parallel_blocks(static_cast<std::int64_t>(nf), kBlock, [&](std::int64_t begin, std::int64_t end) {
    Index hint = kInvalidIndex;
    for (std::int64_t i = begin; i < end; ++i) {
      const auto v = static_cast<std::size_t>(i);
      const Vec3f& p = formed.vertices[v];
      const auto c = hint == kInvalidIndex ? field->closest(p) : field->closest_near(p, hint);
      hint = c.triangle;
      dist[v] = c.distance;
      const auto& tri = posed.triangles[c.triangle];
      const Vec3d l = barycentric(c.point, posed.vertices[tri[0]], posed.vertices[tri[1]], posed.vertices[tri[2]]);
      Influences inf = interpolate(skin, tri, l);
      int corner = 0;
      for (int k = 1; k < 3; ++k)
        if (l[k] > l[corner]) corner = k;
      const Index near_vertex = tri[static_cast<std::size_t>(corner)];
      if (!(inf.weights[0] > 0.0f)) {  // corners without weights: the closest corner's dominant joint alone
        inf = {};
        inf.joints[0] = dominant_joint(skin, near_vertex);
        inf.weights[0] = 1.0f;
      }
      Mat4d m = Mat4d::Zero();
      double ref = 0.0;
      for (int s = 0; s < io::kMaxInfluences; ++s)
        if (inf.weights[s] != 0.0f) {
          m += double(inf.weights[s]) * jt.kd[inf.joints[s]];
          ref += double(inf.weights[s]) * jt.kdet[inf.joints[s]];
        }
      const Mat3d a = m.topLeftCorner<3, 3>();
      const Vec3d pd = p.cast<double>();
      Vec3d x = Vec3d::Constant(std::numeric_limits<double>::quiet_NaN());
      if (std::abs(a.determinant()) > kSingularDet * ref) x = a.inverse() * (pd - m.topRightCorner<3, 1>());
      if (!x.allFinite()) {
        const std::uint16_t d = dominant_joint(skin, near_vertex);
        const Vec3d q_bind = l[0] * target_bind.vertices[tri[0]].cast<double>() +
                             l[1] * target_bind.vertices[tri[1]].cast<double>() +
                             l[2] * target_bind.vertices[tri[2]].cast<double>();
        x = q_bind + jt.kinv[d] * (pd - c.point.cast<double>());
        if (!x.allFinite()) x = q_bind;  // the dominant joint itself is degenerate (a zero scale)
        fell_back[v] = 1;
      }
      out.bind_mesh.vertices[v] = x.cast<float>();
      out.joints[v] = inf.joints;
      out.weights[v] = inf.weights;
      miss[v] = (io::skin_point(kw, inf.joints, inf.weights, out.bind_mesh.vertices[v]) - p).norm();
    }
  });
  for (std::size_t v = 0; v < nf; ++v) {
    out.unreached += fell_back[v];
    out.max_bind_error_m = std::max(out.max_bind_error_m, double(miss[v]));
    out.max_distance_m = std::max(out.max_distance_m, double(dist[v]));
  }
  return out;
}

}  // namespace ff::pose
