// Highway compiles this file once per target (foreach_target re-includes it); HWY_ONCE holds the dispatchers.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "sim/pbf_kernels.cpp"
#include <hwy/foreach_target.h>  // must precede highway.h
#include <hwy/highway.h>

#include "sim/pbf_constraints.h"
#include "sim/pbf_kernels.h"

#include <algorithm>

HWY_BEFORE_NAMESPACE();
namespace ff::sim::HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;
using core::kClusterWidth;

// One j-cluster is kClusterWidth lanes: one vector on AVX2 and AVX-512 (256-bit ops), two on SSE4.
using D = hn::CappedTag<float, kClusterWidth>;

template <class V>
HWY_INLINE float sum_lanes(D d, V v) {
  return hn::GetLane(hn::SumOfLanes(d, v));
}

// 1/√r² from the hardware estimate and one Newton step (~1e-7 relative): a full-width square root and division
// cost ~10× more, and most lanes of a cluster pair are out of range. r² = 0 gives a non-finite value that every
// caller masks (∇W is 0 there).
template <class V>
HWY_INLINE V inv_sqrt(D d, V r2) {
  const V y = hn::ApproximateReciprocalSqrt(r2);
  return hn::Mul(y, hn::NegMulAdd(hn::Mul(hn::Set(d, 0.5f), r2), hn::Mul(y, y), hn::Set(d, 1.5f)));
}

// x_i − x_j for the lanes of a j-cluster starting at `base` (one contiguous load per axis), and |x_i − x_j|².
struct Offsets {
  hn::Vec<D> x, y, z, r2;
};
template <class V>
HWY_INLINE Offsets offsets(D d, V px, V py, V pz, const float* X, const float* Y, const float* Z, std::size_t base) {
  const V rx = hn::Sub(px, hn::Load(d, X + base)), ry = hn::Sub(py, hn::Load(d, Y + base)), rz = hn::Sub(pz, hn::Load(d, Z + base));
  return {rx, ry, rz, hn::MulAdd(rz, rz, hn::MulAdd(ry, ry, hn::Mul(rx, rx)))};
}

// Whether point (x, y, z) is at least r from cluster c's box: then none of its lanes is in range.
HWY_INLINE bool beyond(const core::ClusterSet& s, Index c, float x, float y, float z, float r2) {
  const Vec3f& lo = s.lo[c];
  const Vec3f& hi = s.hi[c];
  const float gx = std::max(std::max(lo.x() - x, x - hi.x()), 0.0f), gy = std::max(std::max(lo.y() - y, y - hi.y()), 0.0f),
              gz = std::max(std::max(lo.z() - z, z - hi.z()), 0.0f);
  return gx * gx + gy * gy + gz * gz >= r2;
}

void LambdaClusters(const core::ClusterSet& s, const core::ClusterPairs& pairs, const PbfLambdaConsts& k,
                    float* density, float* lambda, std::size_t begin, std::size_t end) {
  const D d;
  const hn::RebindToSigned<D> di;
  const std::size_t N = hn::Lanes(d);
  const auto h = hn::Set(d, k.h), h2 = hn::Set(d, k.h2), cgrad = hn::Set(d, k.cgrad), zero = hn::Zero(d);
  const float *X = s.x.data(), *Y = s.y.data(), *Z = s.z.data();
  for (std::size_t c = begin; c < end; ++c) {
    const auto list = pairs.of(c);
    for (std::size_t li = c * kClusterWidth; li < (c + 1) * kClusterWidth; ++li) {
      const Index pi = s.point[li];
      if (pi == kInvalidIndex) {
        lambda[li] = 0.0f;
        continue;
      }
      const auto px = hn::Set(d, X[li]), py = hn::Set(d, Y[li]), pz = hn::Set(d, Z[li]);
      const auto self = hn::Set(di, static_cast<std::int32_t>(li));
      auto sw = zero, g2 = zero, gx = zero, gy = zero, gz = zero;
      for (const Index jc : list) {
        if (beyond(s, jc, X[li], Y[li], Z[li], k.h2)) continue;
        for (std::size_t o = 0; o < kClusterWidth; o += N) {
          const std::size_t base = jc * kClusterWidth + o;
          const Offsets r = offsets(d, px, py, pz, X, Y, Z, base);
          const auto rx = r.x, ry = r.y, rz = r.z, r2 = r.r2;
          auto inside = hn::Lt(r2, h2);
          if (jc == c) inside = hn::And(inside, hn::RebindMask(d, hn::Ne(hn::Iota(di, static_cast<std::int32_t>(base)), self)));
          if (hn::AllFalse(d, inside)) continue;
          const auto q2 = hn::Sub(h2, r2);
          sw = hn::Add(sw, hn::IfThenElseZero(inside, hn::Mul(hn::Mul(q2, q2), q2)));
          const auto inv_len = inv_sqrt(d, r2);
          const auto q = hn::NegMulAdd(r2, inv_len, h);  // h − |r|
          const auto cc = hn::IfThenElseZero(hn::And(inside, hn::Gt(r2, zero)), hn::Mul(hn::Mul(cgrad, hn::Mul(q, q)), inv_len));
          g2 = hn::MulAdd(hn::Mul(cc, cc), r2, g2);  // |∇_j C_i|² = c² |r|²
          gx = hn::MulAdd(cc, rx, gx);
          gy = hn::MulAdd(cc, ry, gy);
          gz = hn::MulAdd(cc, rz, gz);
        }
      }
      const float rho = k.mass * (k.w0 + k.poly6_k * sum_lanes(d, sw));
      density[pi] = rho;
      const Vec3f grad(sum_lanes(d, gx), sum_lanes(d, gy), sum_lanes(d, gz));
      lambda[li] = pbf_lambda(density_constraint(rho, k.rho0), sum_lanes(d, g2) + grad.squaredNorm(), k.epsilon);
    }
  }
}

// The s_corr exponent is a compile-time constant (0 = none), so its power unrolls.
template <int kN>
void DeltaImpl(const core::ClusterSet& s, const core::ClusterPairs& pairs, const float* lambda, const PbfDeltaConsts& k,
               Vec3f* next, std::size_t begin, std::size_t end) {
  const D d;
  const std::size_t N = hn::Lanes(d);
  const auto h = hn::Set(d, k.h), h2 = hn::Set(d, k.h2), kgrad = hn::Set(d, k.kgrad), w_ratio = hn::Set(d, k.w_ratio),
             scorr_c = hn::Set(d, k.scorr_c), zero = hn::Zero(d);
  const float *X = s.x.data(), *Y = s.y.data(), *Z = s.z.data();
  for (std::size_t c = begin; c < end; ++c) {
    const auto list = pairs.of(c);
    for (std::size_t li = c * kClusterWidth; li < (c + 1) * kClusterWidth; ++li) {
      const Index pi = s.point[li];
      if (pi == kInvalidIndex) continue;
      const auto px = hn::Set(d, X[li]), py = hn::Set(d, Y[li]), pz = hn::Set(d, Z[li]), lam_i = hn::Set(d, lambda[li]);
      auto dx = zero, dy = zero, dz = zero;
      for (const Index jc : list) {
        if (beyond(s, jc, X[li], Y[li], Z[li], k.h2)) continue;
        for (std::size_t o = 0; o < kClusterWidth; o += N) {
          const std::size_t base = jc * kClusterWidth + o;
          const Offsets r = offsets(d, px, py, pz, X, Y, Z, base);
          const auto rx = r.x, ry = r.y, rz = r.z, r2 = r.r2;
          // r = 0 (itself, or a coincident particle) has no gradient; beyond h none either.
          const auto use = hn::And(hn::Lt(r2, h2), hn::Gt(r2, zero));
          if (hn::AllFalse(d, use)) continue;
          const auto inv_len = inv_sqrt(d, r2);
          const auto len = hn::Mul(r2, inv_len);
          auto l = hn::Add(lam_i, hn::Load(d, lambda + base));
          if constexpr (kN > 0) {
            const auto q2 = hn::Sub(h2, r2);
            auto ratio = hn::Mul(w_ratio, hn::Mul(hn::Mul(q2, q2), q2));
            auto pw = ratio;
            for (int e = 1; e < kN; ++e) pw = hn::Mul(pw, ratio);
            l = hn::MulAdd(scorr_c, pw, l);
          }
          const auto q = hn::Sub(h, len);
          const auto cc = hn::IfThenElseZero(use, hn::Mul(hn::Mul(hn::Mul(l, kgrad), hn::Mul(q, q)), inv_len));
          dx = hn::MulAdd(cc, rx, dx);
          dy = hn::MulAdd(cc, ry, dy);
          dz = hn::MulAdd(cc, rz, dz);
        }
      }
      const Vec3f xi(X[li], Y[li], Z[li]);
      next[pi] = (xi + k.m_rho0 * Vec3f(sum_lanes(d, dx), sum_lanes(d, dy), sum_lanes(d, dz))).cwiseMax(k.lo).cwiseMin(k.hi);
    }
  }
}

void DeltaClusters(const core::ClusterSet& s, const core::ClusterPairs& pairs, const float* lambda,
                   const PbfDeltaConsts& k, Vec3f* next, std::size_t begin, std::size_t end) {
  switch (k.scorr_n) {  // SolverParams::validate() keeps n in [1, 8]; 0 = s_corr off
    case 0: return DeltaImpl<0>(s, pairs, lambda, k, next, begin, end);
    case 1: return DeltaImpl<1>(s, pairs, lambda, k, next, begin, end);
    case 2: return DeltaImpl<2>(s, pairs, lambda, k, next, begin, end);
    case 3: return DeltaImpl<3>(s, pairs, lambda, k, next, begin, end);
    case 4: return DeltaImpl<4>(s, pairs, lambda, k, next, begin, end);
    case 5: return DeltaImpl<5>(s, pairs, lambda, k, next, begin, end);
    case 6: return DeltaImpl<6>(s, pairs, lambda, k, next, begin, end);
    case 7: return DeltaImpl<7>(s, pairs, lambda, k, next, begin, end);
    default: return DeltaImpl<8>(s, pairs, lambda, k, next, begin, end);
  }
}

}  // namespace ff::sim::HWY_NAMESPACE
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace ff::sim {
HWY_EXPORT(LambdaClusters);
HWY_EXPORT(DeltaClusters);

void pbf_lambda_clusters(const core::ClusterSet& s, const core::ClusterPairs& pairs, const PbfLambdaConsts& k,
                         float* density, float* lambda, std::size_t begin, std::size_t end) {
  HWY_DYNAMIC_DISPATCH(LambdaClusters)(s, pairs, k, density, lambda, begin, end);
}
void pbf_delta_clusters(const core::ClusterSet& s, const core::ClusterPairs& pairs, const float* lambda,
                        const PbfDeltaConsts& k, Vec3f* next, std::size_t begin, std::size_t end) {
  HWY_DYNAMIC_DISPATCH(DeltaClusters)(s, pairs, lambda, k, next, begin, end);
}
}  // namespace ff::sim
#endif
