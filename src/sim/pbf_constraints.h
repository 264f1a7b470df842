#pragma once
// Per-particle PBF maths as pure functions: Macklin & Müller, "Position Based Fluids", SIGGRAPH 2013
// (METHOD.md §c.2), equation numbers theirs. No state, no loops over particles: the solver's loops call these,
// tests call them alone. The position update Δp_i = (1/ρ0) Σ_j (λ_i + λ_j + s_corr) ∇W(p_i − p_j) (eq. 14) and
// XSPH viscosity (eq. 17) are in the solver's pair loops.
//
// Symbols: ρ0 calibrated rest density (kg/m³), m particle mass (kg), C_i = ρ_i/ρ0 − 1,
// S_0 = Σ_k |∇_k C_i|² of a resting lattice neighbourhood (1/m²), ε = epsilon·S_0.
#include <algorithm>
#include <cmath>

namespace ff::sim {

/// C_i = max(ρ_i/ρ0 − 1, 0) (eq. 1, with ρ_i of eq. 2): clamped so that the free surface is not pulled together (SPlisHSPlasH does the same).
inline float density_constraint(float density, float rho0) { return std::max(density / rho0 - 1.0f, 0.0f); }

/// λ_i = −C_i / (Σ_k |∇_k C_i|² + ε), m² (eq. 11; ∇_k C_i of eq. 8).
inline float pbf_lambda(float constraint, float grad_sq_sum, float epsilon) {
  return -constraint / (grad_sq_sum + epsilon);
}

/// s_corr = −k (W(r)/W(Δq))ⁿ / S_0 (eq. 13, made dimensionless by S_0: units of λ, m²): a short-range repulsion
/// against clumping (tensile instability).
inline float pbf_scorr(float w_over_wdq, float k, int n, float s0) {
  float p = w_over_wdq;
  float acc = 1.0f;
  for (int i = 0; i < n; ++i) acc *= p;
  return -k * acc / s0;
}

/// Largest stable-ish sub-step from the CFL condition: displacement ≤ cfl·d per step.
inline float cfl_dt(float max_speed, float spacing, float cfl, float max_dt) {
  if (!(max_speed > 0.0f)) return max_dt;
  return std::min(max_dt, cfl * spacing / max_speed);
}

}  // namespace ff::sim
