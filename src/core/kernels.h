#pragma once
// SPH kernels in 3D (METHOD.md §c.1), pure inline functions. r = |r|, support h, zero for r >= h.
//   Poly6  W(r) = 315/(64π h⁹) (h² − r²)³             densities and weighted averages
//   Spiky  ∇W(r) = −45/(π h⁶) (h − r)² r̂              every gradient (Müller 2003; PBF practice)
//   Cubic  k = 8/(π h³), q = r/h: k(6q³−6q²+1) q≤½, 2k(1−q)³ ½<q≤1   (SPlisHSPlasH default)
// Kernel objects precompute their constants once per support radius so hot loops only multiply.
#include "core/types.h"

#include <cmath>
#include <numbers>

namespace ff::core {

/// Poly6 kernel with support h (metres). Evaluated from r² so density loops need no sqrt.
struct Poly6 {
  float h = 1.0f, h2 = 1.0f, k = 0.0f, kgrad = 0.0f;
  explicit Poly6(float support) : h(support), h2(support * support) {
    const double hd = support;
    k = static_cast<float>(315.0 / (64.0 * std::numbers::pi * std::pow(hd, 9)));
    kgrad = static_cast<float>(-945.0 / (32.0 * std::numbers::pi * std::pow(hd, 9)));
  }
  /// W(r) in 1/m³ from r² in m².
  float w_r2(float r2) const {
    if (r2 >= h2) return 0.0f;
    const float q = h2 - r2;
    return k * q * q * q;
  }
  float w(float r) const { return w_r2(r * r); }
  float w_zero() const { return k * h2 * h2 * h2; }
  /// ∇W with respect to its argument r (vector from neighbour to particle), 1/m⁴.
  Vec3f grad(const Vec3f& r) const {
    const float r2 = r.squaredNorm();
    if (r2 >= h2) return Vec3f::Zero();
    const float q = h2 - r2;
    return (kgrad * q * q) * r;
  }
};

/// Spiky kernel: value and gradient. The gradient is what PBF uses for every constraint gradient.
struct Spiky {
  float h = 1.0f, h2 = 1.0f, k = 0.0f, kgrad = 0.0f;
  explicit Spiky(float support) : h(support), h2(support * support) {
    const double hd = support;
    k = static_cast<float>(15.0 / (std::numbers::pi * std::pow(hd, 6)));
    kgrad = static_cast<float>(-45.0 / (std::numbers::pi * std::pow(hd, 6)));
  }
  float w(float r) const {
    if (r >= h) return 0.0f;
    const float q = h - r;
    return k * q * q * q;
  }
  /// ∇W(r): points along −r̂ (towards the neighbour) with the usual sign; defined 0 at r = 0.
  Vec3f grad(const Vec3f& r) const {
    const float r2 = r.squaredNorm();
    if (r2 >= h2 || r2 <= 0.0f) return Vec3f::Zero();
    const float len = std::sqrt(r2);
    const float q = h - len;
    return (kgrad * q * q / len) * r;
  }
  /// Same as grad(r) when |r| = len is already known (saves the sqrt in hot loops).
  Vec3f grad(const Vec3f& r, float len) const {
    if (len >= h || len <= 0.0f) return Vec3f::Zero();
    const float q = h - len;
    return (kgrad * q * q / len) * r;
  }
};

/// Cubic spline (Monaghan), support h. Not used by the paper; kept for the samplers and for comparison.
struct CubicSpline {
  float h = 1.0f, k = 0.0f, l = 0.0f;
  explicit CubicSpline(float support) : h(support) {
    const double hd = support;
    k = static_cast<float>(8.0 / (std::numbers::pi * hd * hd * hd));
    l = static_cast<float>(48.0 / (std::numbers::pi * hd * hd * hd));
  }
  float w(float r) const {
    const float q = r / h;
    if (q > 1.0f) return 0.0f;
    if (q <= 0.5f) return k * (6.0f * q * q * q - 6.0f * q * q + 1.0f);
    const float a = 1.0f - q;
    return k * 2.0f * a * a * a;
  }
  Vec3f grad(const Vec3f& r) const {
    const float len = r.norm();
    const float q = len / h;
    if (q > 1.0f || len <= 1e-9f * h) return Vec3f::Zero();
    const Vec3f gradq = r / (len * h);
    if (q <= 0.5f) return l * q * (3.0f * q - 2.0f) * gradq;
    const float a = 1.0f - q;
    return l * (-a * a) * gradq;
  }
};

/// Calls f(i, j, k) for every point (i d, j d, k d) of the cubic lattice of spacing d within ⌈h/d⌉ cells of the
/// origin on each axis, the origin included, k outermost: the resting neighbourhood on which PBF's ρ0 and S_0
/// (sim/pbf_solver.cpp), the control mass (sampling/weights.cpp) and the control S_0 (control/control_targets.cpp)
/// are calibrated. One visiting order for all, so each sum is the same to the last bit wherever it is taken.
template <class F>
void for_each_lattice_point(float d, float h, F&& f) {
  const int reach = static_cast<int>(std::ceil(h / d));
  for (int k = -reach; k <= reach; ++k)
    for (int j = -reach; j <= reach; ++j)
      for (int i = -reach; i <= reach; ++i) f(i, j, k);
}

}  // namespace ff::core
