#include "pose/skinning.h"
#include "pose/skin_eval.h"

#include <Eigen/Geometry>
#include <Eigen/SVD>

#include <cmath>

namespace ff::pose {

double TargetSkin::clip_time(double t) const {
  if (clip < 0 || static_cast<std::size_t>(clip) >= skin.clips.size()) return 0.0;
  const double duration = skin.clips[static_cast<std::size_t>(clip)].duration;
  const double tau = std::max(0.0, spec.speed * (t - spec.start));
  if (!(duration > 0.0)) return 0.0;
  if (!spec.loop) return std::min(tau, duration);
  if (!pingpong) return std::fmod(tau, duration);
  const double phase = std::fmod(tau, 2.0 * duration);
  return phase <= duration ? phase : 2.0 * duration - phase;
}

void TargetSkin::world_joint_matrices(double t, std::vector<io::Mat4f>& out) const {
  clip_joint_matrices(clip_time(t), out);
}

void TargetSkin::clip_joint_matrices(double tau, std::vector<io::Mat4f>& out) const {
  joint_matrices(skin, clip, tau, out);
  const io::Mat4f inv = transform.inverse();
  for (auto& k : out) k = transform * k * inv;
}

// Dual-quaternion skinning (Kavan et al. 2007): each joint's rigid part as a unit dual quaternion (q0, qe), blended
// with the signs aligned to the first influence, normalised, applied. A joint matrix's non-rigid part (an animated
// scale: the scene transform's is conjugated away) is taken out by polar decomposition and blended linearly.
void PosedJoints::set(std::vector<io::Mat4f> K, SkinningMethod method) {
  K_ = std::move(K);
  method_ = method;
  if (method_ != SkinningMethod::DualQuaternion) return;
  q0_.resize(K_.size()), qe_.resize(K_.size()), stretch_.resize(K_.size());
  for (std::size_t j = 0; j < K_.size(); ++j) {
    const Eigen::Matrix3f a = K_[j].topLeftCorner<3, 3>();
    Eigen::JacobiSVD<Eigen::Matrix3f> svd(a, Eigen::ComputeFullU | Eigen::ComputeFullV);
    Eigen::Matrix3f u = svd.matrixU();
    if ((u * svd.matrixV().transpose()).determinant() < 0.0f) u.col(2) *= -1.0f;  // a mirror goes into the stretch
    const Eigen::Matrix3f r = u * svd.matrixV().transpose();
    stretch_[j] = r.transpose() * a;
    q0_[j] = Eigen::Quaternionf(r).normalized();
    const Vec3f t = K_[j].topRightCorner<3, 1>();
    qe_[j] = Eigen::Quaternionf(0.0f, t.x(), t.y(), t.z()) * q0_[j];
    qe_[j].coeffs() *= 0.5f;
  }
}

Vec3f PosedJoints::apply(const std::array<std::uint16_t, io::kMaxInfluences>& joints,
                         const std::array<float, io::kMaxInfluences>& weights, const Vec3f& bind) const {
  if (method_ == SkinningMethod::Linear) return io::skin_point(K_, joints, weights, bind);
  Eigen::Vector4f b0 = Eigen::Vector4f::Zero(), be = Eigen::Vector4f::Zero();
  Eigen::Matrix3f s = Eigen::Matrix3f::Zero();
  const Eigen::Vector4f first = q0_[joints[0]].coeffs();
  for (int k = 0; k < io::kMaxInfluences; ++k) {
    const float w = weights[k];
    if (w == 0.0f) continue;
    const std::size_t j = joints[k];
    const float sign = q0_[j].coeffs().dot(first) < 0.0f ? -1.0f : 1.0f;  // the shorter way round
    b0 += sign * w * q0_[j].coeffs();
    be += sign * w * qe_[j].coeffs();
    s += w * stretch_[j];
  }
  const float n = b0.norm();
  if (!(n > 1e-12f)) return io::skin_point(K_, joints, weights, bind);  // opposite rotations cancelled
  Eigen::Quaternionf q0, qe;
  q0.coeffs() = b0 / n;
  qe.coeffs() = be / n;
  const Vec3f t = 2.0f * (qe * q0.conjugate()).vec();  // translation t = 2 qe q0*
  return q0.toRotationMatrix() * (s * bind) + t;
}

}  // namespace ff::pose
