#pragma once
// Fills fluid sources with particles on one cubic lattice of spacing d anchored at the domain's
// inner corner, so overlapping sources share lattice points (deduplicated) and a filled box is exactly
// the resting lattice the rest density is calibrated to.
#include "core/error.h"
#include "sim/particle_set.h"
#include "sim/solver_params.h"

#include <span>

namespace ff::sim {

/// Largest particle count a scene may create before it is refused with an estimate.
inline constexpr std::size_t kMaxParticles = 50'000'000;

/// Number of lattice points the sources would create (an upper bound when sources overlap).
std::size_t estimate_particle_count(std::span<const FluidSource> sources, const Domain& domain, float spacing);

/// Appends the particles of every source to `particles` (ids continue from the current count).
/// Errors: a source with no lattice point inside the domain, or more than `max_particles` particles.
Status fill_sources(std::span<const FluidSource> sources, const Domain& domain, float particle_radius,
                    ParticleSet& particles, std::size_t max_particles = kMaxParticles);

}  // namespace ff::sim
