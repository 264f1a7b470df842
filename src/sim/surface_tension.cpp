#include "sim/surface_tension.h"

#include "core/pair_loop.h"
#include "core/parallel.h"
#include "core/simd.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <bit>
#include <cmath>
#include <numbers>

namespace ff::sim {
namespace {

// SplitMix64 finaliser: a counter-based generator (the same input gives the same bits on every thread).
std::uint64_t mix64(std::uint64_t z) {
  z += 0x9e3779b97f4a7c15ull;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}

// Uniform in [0, 1) from the top 24 bits.
float unit_float(std::uint64_t bits) { return static_cast<float>(bits >> 40) * 0x1p-24f; }

// A uniformly distributed rotation (Shoemake's random unit quaternion) for one particle and sub-step.
Eigen::Matrix3f random_rotation(Index id, std::uint64_t step_key) {
  const std::uint64_t s = mix64(step_key ^ mix64(static_cast<std::uint64_t>(id) + 0x632be59bd9b4e019ull));
  const float u1 = unit_float(mix64(s + 1)), u2 = unit_float(mix64(s + 2)), u3 = unit_float(mix64(s + 3));
  const float a = std::sqrt(1.0f - u1), b = std::sqrt(u1);
  constexpr float two_pi = 2.0f * std::numbers::pi_v<float>;
  const float t2 = two_pi * u2, t3 = two_pi * u3;
  return Eigen::Quaternionf(b * std::cos(t3), a * std::sin(t2), a * std::cos(t2), b * std::sin(t3)).toRotationMatrix();
}

// One neighbour, broadcast for the sample loop: rotated offset / r1 (x, y, z) and the covering threshold c.
// Sample point p (unit vector) is covered by neighbour j iff ‖r1 p − r_j‖ ≤ r2 ⇔ p · r_j/r1 ≥ (1 + ‖r_j‖²/r1² − r2²/r1²)/2.
struct alignas(16) Coverer {
  __m128 x, y, z, c;
};

constexpr std::size_t kStackNeighbors = 64;

// The points of the Fibonacci set no neighbour covers: their count and the sum of their unit vectors (in the
// rotated frame).
struct FreePoints {
  int count = 0;
  Vec3f sum = Vec3f::Zero();
};

// Eight points at a time: a point stays free while no neighbour covers it (branch-free over the neighbours).
FreePoints free_points(const Coverer* cov, std::size_t count, const float* px, const float* py, const float* pz,
                       int samples, std::size_t groups) {
  using namespace core::simd;
  const __m128 zero = _mm_setzero_ps();
  __m128 fx = zero, fy = zero, fz = zero;
  int free_count = 0;
  const __m128 all = _mm_castsi128_ps(_mm_set1_epi32(-1));
  for (std::size_t g = 0; g < groups; g += 2) {
    const std::size_t k0 = 4 * g, k1 = k0 + 4;
    const __m128 ax = _mm_loadu_ps(px + k0), ay = _mm_loadu_ps(py + k0), az = _mm_loadu_ps(pz + k0);
    const __m128 bx = _mm_loadu_ps(px + k1), by = _mm_loadu_ps(py + k1), bz = _mm_loadu_ps(pz + k1);
    // Padding points (k ≥ N) start covered.
    const auto left = static_cast<std::size_t>(samples);
    __m128 ca = _mm_andnot_ps(first_lanes(left > k0 ? left - k0 : 0), all);
    __m128 cb = _mm_andnot_ps(first_lanes(left > k1 ? left - k1 : 0), all);
    // Every neighbour, no early exit: a data-dependent branch per neighbour costs more than it saves.
    for (std::size_t k = 0; k < count; ++k) {
      const Coverer& c = cov[k];
      const __m128 da = _mm_add_ps(_mm_add_ps(_mm_mul_ps(ax, c.x), _mm_mul_ps(ay, c.y)), _mm_mul_ps(az, c.z));
      const __m128 db = _mm_add_ps(_mm_add_ps(_mm_mul_ps(bx, c.x), _mm_mul_ps(by, c.y)), _mm_mul_ps(bz, c.z));
      ca = _mm_or_ps(ca, _mm_cmpge_ps(da, c.c));
      cb = _mm_or_ps(cb, _mm_cmpge_ps(db, c.c));
    }
    free_count += 8 - std::popcount(static_cast<unsigned>(_mm_movemask_ps(ca) | (_mm_movemask_ps(cb) << 4)));
    fx = _mm_add_ps(fx, _mm_add_ps(_mm_andnot_ps(ca, ax), _mm_andnot_ps(cb, bx)));
    fy = _mm_add_ps(fy, _mm_add_ps(_mm_andnot_ps(ca, ay), _mm_andnot_ps(cb, by)));
    fz = _mm_add_ps(fz, _mm_add_ps(_mm_andnot_ps(ca, az), _mm_andnot_ps(cb, bz)));
  }
  return {free_count, Vec3f(hsum(fx), hsum(fy), hsum(fz))};
}

}  // namespace

std::uint64_t surface_tension_step_key(double time) { return mix64(std::bit_cast<std::uint64_t>(time)); }

int surface_tension_samples(float samples_per_second, float dt) {
  const double n = std::floor(static_cast<double>(samples_per_second) * static_cast<double>(dt));
  return static_cast<int>(std::clamp(n, 1.0, 1e7));
}

std::size_t SurfaceTension::bytes() const {
  return (px_.capacity() + py_.capacity() + pz_.capacity() + curv_.capacity() + final_curv_.capacity()) * sizeof(float) +
         (normal_.capacity() + final_normal_.capacity()) * sizeof(Vec3f) + class_.capacity() + candidates_.capacity();
}

// Spherical Fibonacci points: z_k = 1 − (2k + 1)/N, longitude k · golden angle.
void SurfaceTension::prepare_points(int n) {
  if (n == points_) return;
  points_ = n;
  const std::size_t padded = (static_cast<std::size_t>(n) + 7) / 8 * 8;
  px_.assign(padded, 0.0f);
  py_.assign(padded, 0.0f);
  pz_.assign(padded, 0.0f);
  const double golden = std::numbers::pi * (3.0 - std::sqrt(5.0));
  for (int k = 0; k < n; ++k) {
    const double z = 1.0 - (2.0 * k + 1.0) / n, rho = std::sqrt(std::max(0.0, 1.0 - z * z)), phi = golden * k;
    const auto u = static_cast<std::size_t>(k);
    px_[u] = static_cast<float>(rho * std::cos(phi));
    py_[u] = static_cast<float>(rho * std::sin(phi));
    pz_[u] = static_cast<float>(z);
  }
}

void SurfaceTension::classify(std::span<const Vec3f> x, const core::NeighborList& neighbors,
                              const SurfaceTensionParams& params, std::span<std::uint8_t> candidates) {
  using namespace core::simd;
  const Vec3f* xs = x.data();
  core::parallel_for(static_cast<std::int64_t>(x.size()), [&](std::int64_t ii) {
    const auto i = static_cast<Index>(ii);
    const core::NeighborRange nb = neighbors.of(i);
    const Vec3f xi = xs[i];
    const __m128 qx = broadcast(xi.x()), qy = broadcast(xi.y()), qz = broadcast(xi.z()), zero = _mm_setzero_ps();
    __m128 sx = zero, sy = zero, sz = zero;
    core::for_neighbors4(nb, i, [&](const Index* j, __m128 lanes) {
      const V3 xj = gather(xs, j[0], j[1], j[2], j[3]);
      sx = _mm_add_ps(sx, select(lanes, _mm_sub_ps(xj.x, qx)));
      sy = _mm_add_ps(sy, select(lanes, _mm_sub_ps(xj.y, qy)));
      sz = _mm_add_ps(sz, select(lanes, _mm_sub_ps(xj.z, qz)));
    });
    candidates[i] = surface_candidate(nb.size(), Vec3f(hsum(sx), hsum(sy), hsum(sz)).norm(), params) ? 1 : 0;
  });
}

void SurfaceTension::add_accelerations(std::span<const Vec3f> x, std::span<const Index> id,
                                       const core::NeighborList& neighbors, const SurfaceTensionParams& params,
                                       float dt, std::uint64_t step_key, std::span<Vec3f> a) {
  if (params.sigma == 0.0f) return add_accelerations(x, id, neighbors, {}, params, dt, step_key, a);
  candidates_.resize(x.size());
  classify(x, neighbors, params, candidates_);
  add_accelerations(x, id, neighbors, candidates_, params, dt, step_key, a);
}

void SurfaceTension::add_accelerations(std::span<const Vec3f> x, std::span<const Index> id,
                                       const core::NeighborList& neighbors, std::span<const std::uint8_t> candidates,
                                       const SurfaceTensionParams& params, float dt, std::uint64_t step_key,
                                       std::span<Vec3f> a) {
  const std::size_t n = x.size();
  class_.resize(n);
  normal_.resize(n);
  curv_.resize(n);
  final_normal_.resize(n);
  final_curv_.resize(n);
  if (params.sigma == 0.0f || n == 0) {
    std::fill(class_.begin(), class_.end(), std::uint8_t{0});
    std::fill(normal_.begin(), normal_.end(), Vec3f::Zero());
    std::fill(curv_.begin(), curv_.end(), 0.0f);
    std::fill(final_normal_.begin(), final_normal_.end(), Vec3f::Zero());
    std::fill(final_curv_.begin(), final_curv_.end(), 0.0f);
    return;
  }
  const int samples = surface_tension_samples(params.samples_per_second, dt);
  prepare_points(samples);
  estimate_surface(x, id, neighbors, candidates, params, step_key);   // step 2
  smooth_and_accelerate(x, neighbors, params, a);                     // step 3
}

void SurfaceTension::estimate_surface(std::span<const Vec3f> x, std::span<const Index> id,
                                      const core::NeighborList& neighbors, std::span<const std::uint8_t> candidates,
                                      const SurfaceTensionParams& params, std::uint64_t step_key) {
  using namespace core::simd;
  const std::size_t n = x.size();
  const int samples = points_;
  const std::size_t groups = px_.size() / 4;  // groups of four points, an even number

  const float h = params.support, inv_h = 1.0f / h, ratio = params.r2_ratio;
  const float half_gap = 0.5f * (1.0f - ratio * ratio);  // (1 − r2²/r1²)/2
  // κ(f) = −(2/r1)(1 − r2²/r1²)^(−1/2) cos(arccos(1 − 2f) + arcsin(r2/r1))
  const double kappa_scale = -2.0 / double(h) / std::sqrt(1.0 - double(ratio) * ratio);
  const double kappa_shift = std::asin(double(ratio));
  const double inv_samples = 1.0 / samples;

  const Vec3f* xs = x.data();
  const float* px = px_.data();
  const float* py = py_.data();
  const float* pz = pz_.data();
  std::uint8_t* cls = class_.data();
  Vec3f* nrm = normal_.data();
  float* crv = curv_.data();

  core::parallel_for(static_cast<std::int64_t>(n), [&](std::int64_t ii) {
    const auto i = static_cast<Index>(ii);
    cls[i] = static_cast<std::uint8_t>(SurfaceClass::Interior);
    nrm[i] = Vec3f::Zero();
    crv[i] = 0.0f;
    if (!candidates[i]) return;
    const core::NeighborRange nb = neighbors.of(i);
    const std::size_t count = nb.size();
    const Vec3f xi = xs[i];

    // The neighbours in the frame of the rotated point set, scaled to the unit sphere.
    const Eigen::Matrix3f rot = random_rotation(id[i], step_key);
    Coverer stack[kStackNeighbors];
    std::vector<Coverer> heap;
    Coverer* cov = stack;
    if (count > kStackNeighbors) {
      heap.resize(count);
      cov = heap.data();
    }
    for (std::size_t k = 0; k < count; ++k) {
      const Vec3f r = (xs[nb[k]] - xi) * inv_h;
      const Vec3f q = rot.transpose() * r;
      cov[k] = {broadcast(q.x()), broadcast(q.y()), broadcast(q.z()), broadcast(0.5f * r.squaredNorm() + half_gap)};
    }
    const FreePoints free = free_points(cov, count, px, py, pz, samples, groups);
    const Vec3f dir = rot * free.sum;
    const float len = dir.norm();
    // No free point, or free points without a net direction: a false positive of the classifier.
    if (free.count == 0 || !(len > 1e-6f)) {
      cls[i] = static_cast<std::uint8_t>(SurfaceClass::Covered);
      return;
    }
    cls[i] = static_cast<std::uint8_t>(SurfaceClass::Surface);
    nrm[i] = dir / len;
    const double f = free.count * inv_samples;
    crv[i] = static_cast<float>(kappa_scale * std::cos(std::acos(1.0 - 2.0 * f) + kappa_shift));
  });
}

void SurfaceTension::smooth_and_accelerate(std::span<const Vec3f> x, const core::NeighborList& neighbors,
                                           const SurfaceTensionParams& params, std::span<Vec3f> a) {
  // Blend with the surface neighbours (weights 1 − r/h) and add the acceleration.
  const float inv_h = 1.0f / params.support;
  const float tau = params.tau, c_acc = -params.sigma / params.mass;
  const Vec3f* xs = x.data();
  const std::uint8_t* cls = class_.data();
  const Vec3f* nrm = normal_.data();
  const float* crv = curv_.data();
  Vec3f* out = a.data();
  Vec3f* fn = final_normal_.data();
  float* fc = final_curv_.data();
  core::parallel_for(static_cast<std::int64_t>(x.size()), [&](std::int64_t ii) {
    const auto i = static_cast<Index>(ii);
    fn[i] = Vec3f::Zero();
    fc[i] = 0.0f;
    if (cls[i] != static_cast<std::uint8_t>(SurfaceClass::Surface)) return;
    const Vec3f xi = xs[i];
    Vec3f nsum = Vec3f::Zero();
    float ksum = 0.0f, wsum = 0.0f;
    for (Index j : neighbors.of(i)) {
      if (cls[j] != static_cast<std::uint8_t>(SurfaceClass::Surface)) continue;
      const float w = 1.0f - (xs[j] - xi).norm() * inv_h;
      nsum += w * nrm[j];
      ksum += w * crv[j];
      wsum += w;
    }
    const float nlen = nsum.norm();
    if (nlen > 0.0f) nsum /= nlen;
    Vec3f ni = (1.0f - tau) * nrm[i] + tau * nsum;
    const float ilen = ni.norm();
    ni = ilen > 1e-6f ? Vec3f(ni / ilen) : nrm[i];
    const float ki = ((1.0f - tau) * crv[i] + tau * ksum) / ((1.0f - tau) + tau * wsum);
    fn[i] = ni;
    fc[i] = ki;
    out[i] += (c_acc * ki) * ni;
  });
}

}  // namespace ff::sim
