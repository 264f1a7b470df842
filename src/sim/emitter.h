#pragma once
// Fills fluid sources with particles on one cubic lattice of spacing d anchored at the domain's
// inner corner, so overlapping sources share lattice points (deduplicated) and a filled box is exactly
// the resting lattice the rest density is calibrated to.
#include "core/error.h"
#include "sim/particle_set.h"
#include "sim/solver_params.h"

#include <span>
#include <vector>

namespace ff::sim {

/// Largest particle count a scene may create before it is refused with an estimate.
inline constexpr std::size_t kMaxParticles = 50'000'000;

/// Number of lattice points the sources would create (an upper bound when sources overlap).
std::size_t estimate_particle_count(std::span<const FluidSource> sources, const Domain& domain, float spacing);

/// Boxes that fill_sources turns into exactly `count` particles: the lattice points of `column`'s footprint (x, z)
/// in whole layers from its lowest one up, then a last part layer row by row, so that a column sized to a volume
/// holds that volume and not the whole layers that fit (a flat target's column of 4.5 layers made 4). One to
/// three boxes (none for count 0), each reaching half a spacing past its outer lattice points. Empty when the
/// footprint holds no lattice point of the domain.
std::vector<FluidSource> boxes_for_count(const FluidSource& column, const Domain& domain, float particle_radius,
                                         std::size_t count);

/// Appends the particles of every source to `particles` (ids continue from the current count).
/// Errors: a source with no lattice point inside the domain, or more than `max_particles` particles.
Status fill_sources(std::span<const FluidSource> sources, const Domain& domain, float particle_radius,
                    ParticleSet& particles, std::size_t max_particles = kMaxParticles);

}  // namespace ff::sim
