#pragma once
// Surface tension of Zorilla, Ritter, Sappl, Rauch, Harders (CGVC 2019 / Computers 2020), the 2019 step of
// SPlisHSPlasH's SurfaceTension_ZorillaRitter2020 (METHOD.md §a.4 eq. 13, §c.6):
//   1. classify: com_i = ‖Σ_j (x_j − x_i)/h‖ / n_i; i is "surface" if n_i ≤ k·com_i + d_c (k = 74.69, d_c = 12).
//   2. Monte Carlo, surface particles only: N = ⌊C_sd·Δt⌋ (≥ 1) points on the sphere of radius r1 = h around x_i;
//      a point is covered if it lies within r2 = 0.8·r1 of a neighbour. With f = uncovered fraction:
//        n̂_i = normalised Σ (uncovered points − x_i),
//        κ_i = −(2/r1)(1 − r2²/r1²)^(−1/2) cos(arccos(1 − 2f) + arcsin(r2/r1)).
//      A classified particle with no uncovered point (or no net direction) is a false positive: no force.
//   3. smooth over surface neighbours with weights w = 1 − r/h, τ = 0.5:
//        n̂ = normalise((1 − τ) n̂_i + τ normalise(Σ w n̂_j)),  κ = ((1 − τ) κ_i + τ Σ w κ_j) / ((1 − τ) + τ Σ w),
//      and a_i += −(σ/m) κ n̂_i.
//
// Geometry of κ: for a particle on the surface of a ball of radius R the covered region is the ball dilated by
// r2, and the formula gives κ ≈ 1/R (the mean curvature, not the sum 2/R of both principal curvatures). A flat
// surface of particles reads κ ≈ +0.1/h, because the gaps between particles uncover slightly more than the
// continuum's 10 % of the sphere.
//
// Scale and limits (measured): the force is σκ per particle, with no particle area in it (SPlisHSPlasH's form), so
// σ = 0.05 gives σ/m = 0.4 at r = 0.025 m (m = 0.125 kg) but 6.25 at r = 0.01 m (m = 8 g); with κ ∝ 1/h the same
// shape feels ~40× the acceleration at the finer spacing, noise included. A particle just below the surface sees
// almost its whole sphere covered, and the formula (which assumes x_i on the surface) reads that as strong
// concavity (κ → −2/h as f → 0⁺). With the default N (≈ 83) such particles mostly read f = 0 (no force); with many
// points (C_sd·Δt in the hundreds) they are pushed outward every step, which blew a zero-gravity droplet apart at
// r = 0.01 m from C_sd = 3e4 on (r = 0.025 m stayed stable up to C_sd = 1e6).
//
// Sample points: a spherical Fibonacci set of N points (shared by all particles of a call), turned by a uniformly
// random rotation per particle and sub-step. Every point is then uniform on the sphere (the estimate of f is
// unbiased, as with independent points) but the set is stratified, so f has a much smaller variance than with N
// independent points (randomised quasi-Monte Carlo; SPlisHSPlasH's 2020 step uses a Halton table for the same
// reason). The rotation comes from a counter-based hash of (particle id, step key): results do not depend on the
// thread count, the particle order or the number of calls made before.
//
// Cost: the classification needs Σ_j (x_j − x_i) over all particles (the solver sums it in its density pass; a
// standalone SIMD pass is here too), the Monte Carlo runs on candidates only (N × n_i dot products, eight points
// per pair of SSE registers, branch-free), then one smoothing pass that skips non-surface particles.
#include "core/neighbor_grid.h"
#include "core/types.h"

#include <cstdint>
#include <span>
#include <vector>

namespace ff::sim {

struct SurfaceTensionParams {
  float sigma = 0.05f;                 ///< σ (eq. 13); the force is σκ n̂ (SPlisHSPlasH's form), a = −(σ/m) κ n̂
  float samples_per_second = 10000.f;  ///< C_sd: N = ⌊C_sd·Δt⌋ points per surface particle and sub-step (≥ 1)
  float support = 0.1f;                ///< r1 = h, m (the neighbour-list radius)
  float mass = 0.125f;                 ///< m_p, kg
  float r2_ratio = 0.8f;               ///< r2 / r1
  float tau = 0.5f;                    ///< neighbour smoothing weight τ
  float class_k = 74.688796680497925f; ///< classifier slope k
  float class_d = 12.0f;               ///< classifier offset d_c
};

/// Per-particle class of the last call.
enum class SurfaceClass : std::uint8_t {
  Interior = 0,  ///< not classified as surface (or no neighbours)
  Surface = 1,   ///< surface with uncovered samples: carries n̂ and κ
  Covered = 2,   ///< classified as surface, but every sample was covered (a false positive): no force
};

/// A key that changes every sub-step and repeats on a resumed run: the bits of the sub-step's start time.
std::uint64_t surface_tension_step_key(double time);

/// Number of Monte-Carlo points per surface particle in a sub-step of dt seconds.
int surface_tension_samples(float samples_per_second, float dt);

/// The classifier: a particle with `count` neighbours whose offsets x_j − x_i sum to a vector of length
/// `offset_sum` (m) is a surface candidate iff count > 0 and count ≤ k · offset_sum/(h · count) + d_c.
inline bool surface_candidate(std::size_t count, float offset_sum, const SurfaceTensionParams& p) {
  if (count == 0) return false;  // a lone particle: no neighbour defines a surface (as SPlisHSPlasH)
  const auto n = static_cast<float>(count);
  return n <= p.class_k * (offset_sum / (p.support * n)) + p.class_d;
}

/// Holds the per-particle scratch between calls (reuse one object to avoid reallocations).
class SurfaceTension {
 public:
  /// Adds −(σ/m) κ_i n̂_i to a[i] for every surface particle. x, id and a have one entry per particle; the
  /// neighbour list is the fluid's (radius = support, self excluded) built on x. Does nothing when σ = 0.
  void add_accelerations(std::span<const Vec3f> x, std::span<const Index> id, const core::NeighborList& neighbors,
                         const SurfaceTensionParams& params, float dt, std::uint64_t step_key, std::span<Vec3f> a);
  /// The same with the classification done by the caller (the solver fuses the offset sum into its density
  /// pass): candidates[i] != 0 where surface_candidate() holds.
  void add_accelerations(std::span<const Vec3f> x, std::span<const Index> id, const core::NeighborList& neighbors,
                         std::span<const std::uint8_t> candidates, const SurfaceTensionParams& params, float dt,
                         std::uint64_t step_key, std::span<Vec3f> a);

  /// The classification pass on its own: candidates[i] = surface_candidate(...) for every particle.
  static void classify(std::span<const Vec3f> x, const core::NeighborList& neighbors, const SurfaceTensionParams& params,
                       std::span<std::uint8_t> candidates);

  // Results of the last call, indexed like its x (for tests and diagnostics).
  std::span<const std::uint8_t> classes() const { return class_; }  ///< SurfaceClass values
  std::span<const Vec3f> raw_normals() const { return normal_; }    ///< Monte-Carlo n̂ (0 unless Surface)
  std::span<const float> raw_curvatures() const { return curv_; }   ///< Monte-Carlo κ, 1/m
  std::span<const Vec3f> normals() const { return final_normal_; }  ///< smoothed n̂
  std::span<const float> curvatures() const { return final_curv_; } ///< smoothed κ, 1/m
  /// Bytes held (capacity), for the solver's memory estimate.
  std::size_t bytes() const;

 private:
  void prepare_points(int n);
  /// Step 2: the Monte Carlo normal and curvature of every candidate (class_, normal_, curv_).
  void estimate_surface(std::span<const Vec3f> x, std::span<const Index> id, const core::NeighborList& neighbors,
                        std::span<const std::uint8_t> candidates, const SurfaceTensionParams& params,
                        std::uint64_t step_key);
  /// Step 3: smoothed over surface neighbours (final_normal_, final_curv_) and added to `a`.
  void smooth_and_accelerate(std::span<const Vec3f> x, const core::NeighborList& neighbors,
                             const SurfaceTensionParams& params, std::span<Vec3f> a);

  int points_ = 0;  // size of the point set below
  std::vector<float> px_, py_, pz_;  // spherical Fibonacci set, unit radius, padded to a multiple of 8
  std::vector<std::uint8_t> class_, candidates_;
  std::vector<Vec3f> normal_, final_normal_;
  std::vector<float> curv_, final_curv_;
};

}  // namespace ff::sim
