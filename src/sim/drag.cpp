#include "sim/drag.h"

#include "core/pair_loop.h"
#include "core/parallel.h"
#include "core/simd.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace ff::sim {
namespace {

// Gissler et al. / SPlisHSPlasH constants.
constexpr double kCF = 1.0 / 3.0, kCk = 8.0, kCd = 5.0, kCb = 0.5;
constexpr double kSigmaLiquid = 0.0724, kMuLiquid = 0.00102, kMuAir = 0.00001845;
constexpr double kFullNeighbors = 38.0 * 2.0 / 3.0;  // ⅔ of a full SPlisHSPlasH neighbourhood

}  // namespace

DragModel::DragModel(const DragParams& p) {
  const double pi = std::numbers::pi, d = p.spacing, rho_l = p.liquid_density, rho_a = p.air_density;
  const double L = std::cbrt(0.75 / pi) * d;
  const double inv_td = 0.5 * kCd * kMuLiquid / (rho_l * L * L), td = 1.0 / inv_td;
  const double omega2 = std::max(kCk * kSigmaLiquid / (rho_l * L * L * L) - inv_td * inv_td, 0.0);
  const double omega = std::sqrt(omega2);
  double c_def = 1.0;  // an overdamped droplet (ω = 0 only for spacings below ~10 nm)
  if (omega > 0.0) {
    // Eq. (6) as SPlisHSPlasH writes it (the argument of atan clamped to ±π/2), then eq. (7).
    const double val = std::clamp(std::sqrt(td * td * omega2 + 1.0) + td * omega, -0.5 * pi, 0.5 * pi);
    const double t_max = -2.0 * (std::atan(val) - pi) / omega;
    c_def = 1.0 - std::exp(-t_max / td) * (std::cos(omega * t_max) + std::sin(omega * t_max) / (omega * td));
  }
  L_ = static_cast<float>(L);
  y_coeff_ = static_cast<float>(kCF * (rho_a * L / kSigmaLiquid) * c_def / (kCk * kCb));  // eq. (8) without ‖v‖²
  re_coeff_ = static_cast<float>(rho_a * L / kMuAir);
  d2_ = static_cast<float>(d * d);
  acc_ = static_cast<float>(p.scale * 0.5 * rho_a / p.mass);
}

Vec3f DragModel::acceleration(const Vec3f& v, std::size_t count, __m128 best) const {
  const float speed2 = v.squaredNorm();
  if (!(speed2 > 1e-12f)) return Vec3f::Zero();
  best = _mm_max_ps(best, _mm_movehl_ps(best, best));
  best = _mm_max_ss(best, _mm_shuffle_ps(best, best, 1));
  const float w = std::clamp(1.0f - std::sqrt(_mm_cvtss_f32(best)), 0.0f, 1.0f);  // eq. (15)
  if (w == 0.0f) return Vec3f::Zero();
  const float speed = std::sqrt(speed2);
  const auto n = static_cast<float>(count);
  const float phi = std::min(n, static_cast<float>(kFullNeighbors)) / static_cast<float>(kFullNeighbors);
  float cd = 1.0f, area = d2_;  // a full neighbourhood: C_D = 1, A = d²
  if (phi < 1.0f) {
    const float y = std::min(speed2 * y_coeff_, 1.0f);                        // eq. (8)
    const float re = 2.0f * std::max(re_coeff_ * speed, 0.1f);
    const float cd_sphere = re <= 1000.0f ? 24.0f / re * (1.0f + std::pow(re, 2.0f / 3.0f) / 6.0f) : 0.424f;
    const float cd_liu = cd_sphere * (1.0f + 2.632f * y);                     // eq. (9)
    cd = count == 0 ? cd_liu : (1.0f - phi) * cd_liu + phi;                   // eq. (10)
    const float r = L_ * (1.0f + static_cast<float>(kCb) * y);                // L + C_b L y
    area = (1.0f - phi) * std::numbers::pi_v<float> * r * r + phi * d2_;     // eqs. (12), (13)
  }
  return (-acc_ * speed * cd * area * w) * v;  // eq. (14): s ½ ρ_a ‖v_rel‖ v_rel C_D A / m, v_rel = −v
}

void add_drag(std::span<const Vec3f> x, std::span<const Vec3f> v, const core::NeighborList& neighbors,
              const DragParams& params, std::span<Vec3f> a) {
  using namespace core::simd;
  if (params.scale == 0.0f || x.empty()) return;
  const DragModel model(params);
  const Vec3f* xs = x.data();
  const Vec3f* vs = v.data();
  Vec3f* out = a.data();
  core::parallel_for(static_cast<std::int64_t>(x.size()), [&](std::int64_t ii) {
    const auto i = static_cast<Index>(ii);
    const Vec3f dir = DragModel::direction(vs[i]);
    if (dir == Vec3f::Zero()) return;
    const core::NeighborRange nb = neighbors.of(i);
    const Vec3f xi = xs[i];
    const __m128 qx = broadcast(xi.x()), qy = broadcast(xi.y()), qz = broadcast(xi.z());
    const __m128 ux = broadcast(dir.x()), uy = broadcast(dir.y()), uz = broadcast(dir.z());
    __m128 best = _mm_setzero_ps();
    core::for_neighbors4(nb, i, [&](const Index* j, __m128 lanes) {
      const V3 xj = gather(xs, j[0], j[1], j[2], j[3]);
      const __m128 rx = _mm_sub_ps(qx, xj.x), ry = _mm_sub_ps(qy, xj.y), rz = _mm_sub_ps(qz, xj.z);
      const __m128 r2 = _mm_add_ps(_mm_add_ps(_mm_mul_ps(rx, rx), _mm_mul_ps(ry, ry)), _mm_mul_ps(rz, rz));
      best = DragModel::occlusion(best, ux, uy, uz, rx, ry, rz, r2, lanes);
    });
    out[i] += model.acceleration(vs[i], nb.size(), best);
  });
}

}  // namespace ff::sim
