#pragma once
// Air drag of Gissler, Band, Peer, Ihmsen, Teschner, "Approximate Air-Fluid Interactions for SPH" (VRIPHYS 2017),
// as SPlisHSPlasH's DragForce_Gissler2017 (METHOD.md §a.4 eq. 14, §c.7). Per particle, v_rel = v_air − v_i with
// v_air = 0:
//   L = (3/(4π))^(1/3) d; droplet deformation (TAB): t_d = 2ρ_l L²/(C_d μ_l), ω² = C_k σ_l/(ρ_l L³) − 1/t_d²,
//   t_max, c_def from the damped oscillator; y_max = min(1, ‖v_rel‖² C_F ρ_a L c_def/(σ_l C_k C_b));
//   Re = 2 max(ρ_a ‖v_rel‖ L/μ_a, 0.1); C_D,sphere = 24/Re (1 + Re^(2/3)/6) for Re ≤ 1000, else 0.424;
//   C_D,Liu = C_D,sphere (1 + 2.632 y_max); φ_n = min(n_i, ⅔·38)/(⅔·38);
//   C_D = (1 − φ_n) C_D,Liu + φ_n (C_D,Liu when n_i = 0);
//   A_unocc = (1 − φ_n) π (L + C_b L y_max)² + φ_n d²; occlusion w = clamp(1 − max(0, max_j v̂_rel · x̂_ij), 0, 1),
//   x̂_ij = (x_i − x_j)/‖x_i − x_j‖; A = w A_unocc;
//   a_i += s · ½ ρ_a ‖v_rel‖ v_rel C_D A / m.
// Liquid constants are water's (σ_l = 0.0724 N/m, μ_l = 1.02e-3 Pa·s), μ_a = 1.845e-5 Pa·s, as in SPlisHSPlasH.
// The acceleration is tiny at the seed's settings (interior particles are occluded; s = 0.01): it mostly slows spray.
#include "core/neighbor_grid.h"
#include "core/simd.h"
#include "core/types.h"

#include <cmath>
#include <span>

namespace ff::sim {

struct DragParams {
  float scale = 0.01f;           ///< s (eq. 14); 0 = off
  float air_density = 1.2931f;   ///< ρ_a, kg/m³
  float liquid_density = 1000.f; ///< ρ_l, kg/m³ (the physical rest density)
  float spacing = 0.05f;         ///< d, m
  float mass = 0.125f;           ///< m_p, kg
};

/// The drag of one particle from its velocity, neighbour count and occlusion. The occlusion needs a pass over the
/// neighbours; the solver folds it into its XSPH pass (same helpers, same results), add_drag() runs its own.
class DragModel {
 public:
  explicit DragModel(const DragParams& params);

  /// v̂_rel = −v/‖v‖ (air at rest), or zero for a particle slower than 1e-6 m/s (it feels no drag).
  static Vec3f direction(const Vec3f& v) {
    const float s2 = v.squaredNorm();
    return s2 > 1e-12f ? Vec3f(-v / std::sqrt(s2)) : Vec3f::Zero();
  }
  /// One group of four neighbours into the occlusion maximum: best = max(best, (v̂·r)²/‖r‖²) over lanes with
  /// v̂·r > 0, r = x_i − x_j (so √best = max(0, max_j v̂_rel · x̂_ij) without a square root per pair).
  static __m128 occlusion(__m128 best, __m128 ux, __m128 uy, __m128 uz, __m128 rx, __m128 ry, __m128 rz, __m128 r2,
                          __m128 lanes) {
    const __m128 zero = _mm_setzero_ps();
    const __m128 dot = _mm_add_ps(_mm_add_ps(_mm_mul_ps(ux, rx), _mm_mul_ps(uy, ry)), _mm_mul_ps(uz, rz));
    const __m128 use = _mm_and_ps(_mm_and_ps(lanes, _mm_cmpgt_ps(r2, zero)), _mm_cmpgt_ps(dot, zero));
    return _mm_max_ps(best, _mm_and_ps(use, _mm_div_ps(_mm_mul_ps(dot, dot), r2)));
  }
  /// a_drag of a particle with velocity v, `count` neighbours and occlusion lanes `best` (see occlusion()), m/s².
  Vec3f acceleration(const Vec3f& v, std::size_t count, __m128 best) const;

  /// The per-run coefficients of acceleration(), for the GPU's force pass (gpu/shaders/pbf_force.comp).
  struct Coefficients {
    float L = 0, y_coeff = 0, re_coeff = 0, d2 = 0, acc = 0;
  };
  Coefficients coefficients() const { return {L_, y_coeff_, re_coeff_, d2_, acc_}; }

 private:
  float L_ = 0, y_coeff_ = 0, re_coeff_ = 0, d2_ = 0, acc_ = 0;
};

/// Adds the drag acceleration to a[i] for every particle moving faster than 1e-6 m/s. x, v and a have one entry
/// per particle; the neighbour list is the fluid's (self excluded) built on x. Does nothing when scale = 0.
void add_drag(std::span<const Vec3f> x, std::span<const Vec3f> v, const core::NeighborList& neighbors,
              const DragParams& params, std::span<Vec3f> a);

}  // namespace ff::sim
