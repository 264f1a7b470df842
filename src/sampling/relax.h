#pragma once
// Blue-noise relaxation of volume samples. METHOD.md §c.3 describes SPlisHSPlasH's SPH relaxations (Jiang et al. 2015,
// Kugelstadt et al. 2021); what is used is Jiang's idea of a repulsive pressure in its simplest form: a soft pair
// potential (1 − r/r_c)³ of range r_c = 1.75 d minimised by annealed gradient descent with heavy-ball momentum (Polyak
// 1964), plus a projection of every sample shallower than `boundary_depth`·d back to that depth along the SDF gradient.
// With N = V/d³ the set stays under slight pressure, so it spreads evenly up to the surface layer and voids close. A
// half-strength repulsion by each sample's mirror image across the surface keeps the surface layer about d/2 deep, so
// thin walls stay covered. The two position-based forms that lost (a PBF density projection, hard minimum-distance
// constraints) and the figures are in bench/RESULTS.md, "Sampling: the relaxation".
#include "core/progress.h"
#include "core/types.h"
#include "sampling/sdf_grid.h"

#include <span>
#include <vector>

namespace ff::sampling {

struct RelaxParams {
  float spacing = 0.0f;          ///< d, m
  int steps = 30;                ///< relaxation steps
  float reach = 1.75f;           ///< r_c of the repulsion, in d
  float mirror = 0.5f;           ///< strength of the repulsion by the sample's mirror image across the surface
  float step_size = 0.1f;        ///< mean displacement of the first step, in d (annealed to a fifth)
  float boundary_depth = 0.15f;  ///< minimum depth below the surface, in d (Kugelstadt: 0.5 d; shallower
                                 ///< keeps edges and corners covered within 0.9 d)
  float momentum = 0.75f;        ///< share of a sample's last move added to its next (0: plain gradient descent;
                                 ///< 30 steps at 0.75 spread samples more evenly than 100 at 0: bench/RESULTS.md)
  float max_move = 0.1f;         ///< largest displacement of one sample per step, in d (0.2 spread them as evenly,
                                 ///< but with momentum many samples run at the cap and the Verlet list was rebuilt
                                 ///< every other step; bench/RESULTS.md)
};

/// Relaxes `x` in place (the order of the samples changes: they are kept in cell order).
void relax_samples(std::vector<Vec3f>& x, const SdfGrid& sdf, const RelaxParams& params,
                   core::Progress& progress = core::null_progress());

/// Makes the spacing rules hold exactly after relaxation: drops every sample closer than `min_distance` to
/// an earlier one (cell order), then adds a sample at every inside SDF node, and every given surface
/// point, that has none within `min_distance` (thin tips the relaxation emptied). Returns the number
/// dropped; `added` the number added.
std::size_t enforce_spacing(std::vector<Vec3f>& x, const SdfGrid& sdf, float min_distance,
                            std::span<const Vec3f> surface = {}, std::size_t* added = nullptr);

/// Puts samples shallower than `depth` (m) back at that depth (one projection; used after sampling steps).
void push_inside(std::span<Vec3f> x, const SdfGrid& sdf, float depth);

}  // namespace ff::sampling
