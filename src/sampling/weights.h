#pragma once
// Control weights of one target (paper eq. 1–4, 9; METHOD.md §a.2, §a.3), precomputed once:
//   ω_i  = W(0, H_c) / Σ_j W(x_ci − x_cj, H_c)          Shepard self-weight, self included (eq. 2)
//   x̄    = Σ ω_i x_ci / Σ ω_i                            weighted centroid vector (eq. 1)
//   φ_i  = ‖x_ci − x̄‖,  φ̃_i = (φ_i − φ_min)/(φ_max − φ_min) + c   (eq. 3, 4; 1 when φ_max = φ_min)
//   ρ_c,i = m_c Σ_j W(x_ci − x_cj, H_c)                 control density (eq. 9)
// with m_c calibrated so that the median ρ_c of interior samples (whole support inside the target)
// equals the kernel-sum density, at H_c, of a resting fluid lattice of spacing d_c and rest density ρ0.
// W is Poly6.
#include "core/error.h"
#include "sampling/control_set.h"

#include <span>

namespace ff::sampling {

struct WeightParams {
  float support_factor = 3.0f;  ///< H_c / d_c (SamplingParams::support_factor says why 3)
  float phi_offset = 0.05f;     ///< c
  float rest_density = 1000.0f; ///< fluid ρ0, kg/m³
};

/// Fills density, weight, phi, mass, support and centre of `set` (positions and spacing must be set).
/// `depth[i]` is sample i's distance inside the target surface (≥ 0 inside); it selects the interior
/// samples of the mass calibration. Re-orders the samples into cell order (the order carries no meaning).
Status compute_weights(ControlSet& set, std::span<float> depth, const WeightParams& params);

/// Σ_j W(x_i − x_j, h) over all points (self included), per point; exposed for tests.
std::vector<float> kernel_sums(std::span<const Vec3f> points, float h);

/// Kernel-sum density of a resting cubic lattice of spacing d at support h: m Σ_k W(k d, h), m = ρ0 d³.
double lattice_density(float d, float h, float rest_density);

}  // namespace ff::sampling
