#pragma once
// Target sampling (paper §3.2, METHOD.md §a.1): a mesh becomes the control particles of one target.
//   blue-noise (default)  N = V/d³ samples kept from 2N random interior points by sample elimination
//                         (Yuksel 2015), then SPH relaxation (relax.h) — even spacing up to the surface;
//   voxel                 cubic lattice of spacing d, cell centres inside (winding number);
//   surface               N = A/(√3/2 d²) samples kept from 4N random surface points by sample elimination.
// A mesh that encloses no volume (an open sheet) is sampled as a surface shell, with a warning.
#include "core/error.h"
#include "core/progress.h"
#include "io/triangle_mesh.h"
#include "sampling/control_set.h"
#include "sampling/mesh_field.h"
#include "sampling/sampling_params.h"
#include "sampling/sdf_grid.h"

#include <string>
#include <vector>

namespace ff::sampling {

/// What sampling did (for logs, reports and the cache).
struct SampleReport {
  Method method = Method::BlueNoise;  ///< the method used (surface when an open sheet forced it)
  float spacing = 0.0f;               ///< d_c used, m
  double volume = 0.0, area = 0.0;    ///< of the target, m³ / m²
  std::size_t candidates = 0;         ///< random points before elimination (0 for voxel)
  std::size_t samples = 0;            ///< control particles made
  std::size_t dropped = 0;            ///< removed by the sparse-sampling options
  std::size_t repaired_dropped = 0;   ///< blue noise: samples dropped for being closer than 0.85 d
  std::size_t repaired_added = 0;     ///< blue noise: samples added where 0.85 d held none
  double seconds = 0.0;
  /// Wall time per stage, s: mesh field, SDF grid, candidates + elimination, relaxation, spacing repair, weights.
  double t_field = 0, t_sdf = 0, t_init = 0, t_relax = 0, t_repair = 0, t_weights = 0;
  std::vector<std::string> warnings;
};

/// Samples one target into a ControlSet with its weights (weights.h). `target` is stored in the set.
Result<ControlSet> sample_target(const io::TriangleMesh& mesh, const SamplingParams& params, std::uint8_t target = 0,
                                 SampleReport* report = nullptr, core::Progress& progress = core::null_progress());

/// Replaces distances to surfaces hidden inside the volume (faces of one part inside another) by the
/// distance to the real boundary (the sign change), so that the relaxation does not treat them as walls.
void ignore_hidden_surfaces(SdfGrid& sdf);

/// Volume inside the surface of `sdf` (Σ over nodes of a step smoothed over one node spacing), m³.
double enclosed_volume(const SdfGrid& sdf);

/// The spacing `auto_count` samples would have in this field (volume, or the surface of an open sheet).
float automatic_spacing(const MeshField& field, std::size_t auto_count);

/// Samples a target makes at spacing d: V/d³ when sampled as a solid, else a hexagonal packing of its area.
/// sample_target refuses more than 1.5 × max_samples by this count before it builds any grid.
double estimate_sample_count(bool solid, double volume, double area, float d);

// The stages, exposed for tests and benchmarks.
std::vector<Vec3f> voxel_samples(const MeshField& field, float spacing);

/// The solid's volume as cells of a lattice of spacing d: the lattice points of voxel_samples (and one more layer
/// round them), each with the share of its cell the solid covers, clamp(½ − s/d, 0, 1) from its signed distance s
/// (the smoothed step enclosed_volume takes on the SDF grid): 1 deep inside, 0 outside, a fraction next to the
/// surface. Only points with a 6-neighbour on the other side of the surface ask for a distance. Unlike a count of
/// the points inside, a wall 4.9 spacings thick reads 4.9 cells and not the 4 lattice layers that fit: what the
/// fluid is sized by (pipeline/auto_scene.h), so that a thin part gets as much fluid as its samples stand for.
struct LatticeCells {
  std::vector<Vec3f> point;  ///< lattice points whose share is positive
  std::vector<float> share;  ///< (0, 1], the covered share of the point's cell
  double cells() const;      ///< Σ share, summed in order
};
LatticeCells lattice_cells(const MeshField& field, float spacing);
std::vector<Vec3f> random_interior_points(const SdfGrid& sdf, const Aabb& box, std::size_t count, std::uint64_t seed);
std::vector<Vec3f> random_surface_points(const io::TriangleMesh& mesh, std::size_t count, std::uint64_t seed);

}  // namespace ff::sampling
