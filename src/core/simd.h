#pragma once
// Four-wide SSE helpers for the particle pair loops (x86-64-v2 baseline: SSE4.2, no FMA, so results are
// the same on every x86-64 machine that runs the release build).
//
// The pair loops process a particle's neighbours four at a time: indices are decoded into a small
// batch, positions are gathered and transposed into x/y/z registers, and per-lane masks drop the
// lanes that are padding or outside the kernel support. Lane sums are reduced in a fixed order, so a
// result depends only on the neighbour list, never on the thread count.
#include "core/types.h"

#include <immintrin.h>

namespace ff::core::simd {

/// Three coordinates of four points, one register per axis.
struct V3 {
  __m128 x, y, z;
};

/// Points p[a], p[b], p[c], p[d] transposed. Reads exactly 12 bytes per point (no over-read at the end
/// of an array): an 8-byte load of x, y and a 4-byte load of z.
inline V3 gather(const Vec3f* p, Index a, Index b, Index c, Index d) {
  auto xy = [&](Index i) { return _mm_loadl_pi(_mm_setzero_ps(), reinterpret_cast<const __m64*>(p[i].data())); };
  auto z = [&](Index i) { return _mm_load_ss(p[i].data() + 2); };
  const __m128 ab = _mm_unpacklo_ps(xy(a), xy(b));  // xa xb ya yb
  const __m128 cd = _mm_unpacklo_ps(xy(c), xy(d));  // xc xd yc yd
  return {_mm_movelh_ps(ab, cd), _mm_movehl_ps(cd, ab),
          _mm_movelh_ps(_mm_unpacklo_ps(z(a), z(b)), _mm_unpacklo_ps(z(c), z(d)))};
}

inline __m128 gather(const float* p, Index a, Index b, Index c, Index d) { return _mm_setr_ps(p[a], p[b], p[c], p[d]); }

/// Lanes 0..count−1 set (count clamped to 4).
inline __m128 first_lanes(std::size_t count) {
  const __m128i lane = _mm_setr_epi32(0, 1, 2, 3);
  return _mm_castsi128_ps(_mm_cmplt_epi32(lane, _mm_set1_epi32(static_cast<int>(count < 4 ? count : 4))));
}

/// (v0 + v2) + (v1 + v3): a fixed order.
inline float hsum(__m128 v) {
  const __m128 pairs = _mm_add_ps(v, _mm_movehl_ps(v, v));  // v0+v2, v1+v3
  return _mm_cvtss_f32(_mm_add_ss(pairs, _mm_shuffle_ps(pairs, pairs, 1)));
}

/// xⁿ for n ≥ 0 by repeated squaring (log₂ n dependent multiplies instead of n).
inline __m128 pow_int(__m128 x, int n) {
  __m128 r = _mm_set1_ps(1.0f);
  while (n > 0) {
    if (n & 1) r = _mm_mul_ps(r, x);
    x = _mm_mul_ps(x, x);
    n >>= 1;
  }
  return r;
}

inline __m128 broadcast(float v) { return _mm_set1_ps(v); }
inline __m128 select(__m128 mask, __m128 v) { return _mm_and_ps(mask, v); }

}  // namespace ff::core::simd
