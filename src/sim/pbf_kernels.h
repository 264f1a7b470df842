#pragma once
// The PBF solver's Jacobi passes on cluster pairs (core/clusters.h), compiled for every x86 target by Highway and
// dispatched at run time (core/simd_target.h). Each call handles the i-clusters [begin, end) and writes only their
// outputs, so any split over threads gives the same result.
#include "core/clusters.h"
#include "core/types.h"

#include <cstdint>

namespace ff::sim {

struct PbfLambdaConsts {
  float h = 0, h2 = 0;    // Spiky / Poly6 support (one H_p) and its square
  float poly6_k = 0;      // Poly6 W = k (h² − r²)³
  float w0 = 0;           // W(0)
  float mass = 0, rho0 = 0, epsilon = 0;
  float cgrad = 0;        // (m/ρ0) · Spiky kgrad: ∇_j C_i = cgrad (h − r)² r/|r|
};

struct PbfDeltaConsts {
  float h = 0, h2 = 0;
  float kgrad = 0;        // Spiky ∇W = kgrad (h − r)² r/|r|
  float w_ratio = 0;      // Poly6 k / W(Δq): W/W(Δq) = w_ratio (h² − r²)³
  float scorr_c = 0;      // −k_corr / S_0
  int scorr_n = 0;        // 0: no s_corr
  float m_rho0 = 0;       // m/ρ0
  Vec3f lo = Vec3f::Zero(), hi = Vec3f::Zero();  // walls: x* is clamped to them
};

/// The sub-step's forces and prediction (gravity and XSPH; the GPU's force pass, gpu/pbf_device.h).
struct PbfForceConsts {
  Vec3f gravity = Vec3f::Zero();  // m/s²
  float dt = 0;                   // s, the sub-step
  float xsph = 0;                 // XSPH viscosity η / Δt (0: none)
  float mass_poly6_k = 0;         // m · Poly6 k: (m/ρ_j) W_ij = mass_poly6_k (h² − r²)³ / ρ_j
  // Air drag (sim/drag.h, DragModel's coefficients); drag_acc = 0: none.
  float drag_L = 0, drag_y = 0, drag_re = 0, drag_d2 = 0, drag_acc = 0;
  // Surface tension (sim/surface_tension.h): σ at this spacing (0: none), C_sd, and the sub-step's key
  // (surface_tension_step_key of its start time: the caller's, it depends on the time).
  float st_sigma = 0, st_samples_per_second = 0;
  std::uint64_t st_key = 0;
  float vorticity = 0;  // vorticity confinement ε_v, m/s (0: none; the GPU's passes, PbfSolver::vorticity_confinement)
};

/// λ at x* (s.x/y/z): density[point] per particle, lambda in s's padded layout (0 at padding).
void pbf_lambda_clusters(const core::ClusterSet& s, const core::ClusterPairs& pairs, const PbfLambdaConsts& k,
                         float* density, float* lambda, std::size_t begin, std::size_t end);
/// Δx from λ (padded layout): next[point] = clamp(x* + (m/ρ0) Σ_j (λ_i + λ_j + s_corr) ∇W_ij).
void pbf_delta_clusters(const core::ClusterSet& s, const core::ClusterPairs& pairs, const float* lambda,
                        const PbfDeltaConsts& k, Vec3f* next, std::size_t begin, std::size_t end);

}  // namespace ff::sim
