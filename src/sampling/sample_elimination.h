#pragma once
// Yuksel 2015, "Sample Elimination for Generating Poisson Disk Sample Sets" (METHOD.md §c.5):
// from M random candidates keep the N that are best spread, by repeatedly removing the candidate with
// the largest crowding weight Σ_j (1 − d̂_ij/d_max)^α. Deterministic for a given input.
#include "core/progress.h"
#include "core/types.h"

#include <span>
#include <vector>

namespace ff::sampling {

struct EliminationParams {
  float d_max = 0.0f;   ///< 2 r_max: r_max = (V / (4√2 N))^(1/3) in a volume, (A / (2√3 N))^(1/2) on a surface
  float alpha = 8.0f;   ///< weight exponent α
  float beta = 0.65f;   ///< weight limiting β
  float gamma = 1.5f;   ///< weight limiting γ
};

/// r_max of N samples in a volume V (dense packing of spheres, Yuksel eq. 5).
double volume_r_max(double volume, std::size_t n);
/// r_max of N samples on an area A (hexagonal packing).
double surface_r_max(double area, std::size_t n);

/// Indices (ascending) of the `keep` candidates that remain. keep ≥ candidates.size() keeps all.
std::vector<Index> eliminate_samples(std::span<const Vec3f> candidates, std::size_t keep, const EliminationParams& params,
                                     core::Progress& progress = core::null_progress());

}  // namespace ff::sampling
