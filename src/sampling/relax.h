#pragma once
// Blue-noise relaxation of volume samples. METHOD.md §c.3 describes SPlisHSPlasH's SPH relaxations
// (Jiang et al. 2015, Kugelstadt et al. 2021). Two position-based forms were measured on a sphere and a
// box (N = V/d³ samples after sample elimination; /tmp harness, figures in the closing note of issue 3):
//   - PBF density projection, repulsive only: with N = V/d³ the kernel-sum density sits at or below ρ0,
//     the constraint goes slack and the boundary projection clumps samples at the surface
//     (nearest-neighbour minimum 0.38 d);
//   - hard minimum-distance constraints at 1.1 d: even spacing (minimum 0.90 d) but the set jams with
//     voids (largest empty sphere 0.93–1.05 d).
// What is used: Jiang's idea of a repulsive pressure in its simplest form, a soft pair potential
// (1 − r/r_c)³ of range r_c = 1.75 d minimised by annealed gradient descent, plus a projection of every
// sample shallower than `boundary_depth`·d back to that depth along the SDF gradient. With N = V/d³ the
// set stays under slight pressure, so it spreads evenly up to the surface layer and voids close:
// minimum distance 0.89–0.92 d, largest empty sphere 0.83–0.84 d on both shapes. Samples pressed flat
// against the surface left the middle of thin walls (a vase, 2 d thick) uncovered and met at the
// projection in thin parts (the bunny's ears); a half-strength repulsion by each sample's mirror image
// across the surface keeps them about d/2 deep (sphere 0.90 d / 0.82 d, box 0.88 d / 0.81 d).
#include "core/progress.h"
#include "core/types.h"
#include "sampling/sdf_grid.h"

#include <span>
#include <vector>

namespace ff::sampling {

struct RelaxParams {
  float spacing = 0.0f;          ///< d, m
  int steps = 100;               ///< relaxation steps
  float reach = 1.75f;           ///< r_c of the repulsion, in d
  float mirror = 0.5f;           ///< strength of the repulsion by the sample's mirror image across the surface
  float step_size = 0.1f;        ///< mean displacement of the first step, in d (annealed to a fifth)
  float boundary_depth = 0.15f;  ///< minimum depth below the surface, in d (Kugelstadt: 0.5 d; shallower
                                 ///< keeps edges and corners covered within 0.9 d)
  float max_move = 0.2f;         ///< largest displacement of one sample per step, in d
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
