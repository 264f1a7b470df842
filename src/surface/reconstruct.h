#pragma once
// Particles → editable mesh (paper §5.1, METHOD.md §a.7, §c.8, §c.9). The pipeline, one file per stage:
//   sparse_field      φ on a sparse grid of cell d/2 (memory grows with the surface)
//   marching_cubes    welded, watertight by construction (asymptotic decider on ambiguous faces); or, with
//                     SurfaceParams::extraction = MarchingTetrahedra, marching_tetrahedra (6 Kuhn tetrahedra per
//                     cube, the extraction of RMT: the cluster_reduce stage then makes it Treece et al.'s RMT)
//   components        tiny floating components and bubbles dropped (first: no work spent on spray)
//   cluster_reduce    per-node vertex clustering (regularised-marching-tetrahedra style), merged vertices
//                     projected back onto φ = iso
//   smooth            the paper's weighted 1-ring smoothing, eq. 20–21 (with a Taubin back-step by default)
//   decimate          meshoptimizer to an error bound, then to the triangle budget
// The mesh is checked (mesh_check.h) after marching cubes and after every later stage; a stage whose result
// fails the check is undone, so the output is always watertight, 2-manifold, outward and free of degenerate
// triangles. Deterministic: the same mesh for any thread count.
#include "core/error.h"
#include "core/types.h"
#include "io/triangle_mesh.h"
#include "surface/mesh_check.h"
#include "surface/surface_params.h"

#include <cstddef>
#include <span>

namespace ff::surface {

/// What each stage did and cost (seconds of wall time).
struct SurfaceStats {
  std::size_t particles = 0;
  std::size_t candidate_blocks = 0;  ///< 8³-cell blocks evaluated
  std::size_t surface_blocks = 0;    ///< blocks kept (the surface passes through them)
  std::size_t field_bytes = 0;       ///< memory of the kept blocks
  float max_field = 0.0f;            ///< max φ over the grid (below iso: no surface)
  std::size_t mc_vertices = 0, mc_triangles = 0, mc_centres = 0;  ///< of the extraction (cubes or tetrahedra)
  std::size_t removed_components = 0, removed_triangles = 0;
  std::size_t reduced_vertices = 0, reduced_triangles = 0;  ///< after cluster_reduce (= input when skipped)
  std::size_t clusters_merged = 0, clusters_undone = 0;
  std::size_t decimate_passes = 0, decimate_rejected = 0;
  float decimate_error = 0.0f;  ///< m
  bool budget_met = true;
  bool smoothing_undone = false;  ///< smoothing broke a check and was undone
  bool reduction_undone = false;  ///< reduction broke a check and was undone
  double t_field = 0, t_mc = 0, t_components = 0, t_smooth = 0, t_reduce = 0, t_decimate = 0, t_check = 0;
  MeshCheck check;  ///< of the returned mesh
  double total_seconds() const { return t_field + t_mc + t_components + t_smooth + t_reduce + t_decimate + t_check; }
};

/// The surface of `particles` (m) for fluid spacing `spacing` (d, m).
/// Returns a closed, 2-manifold, outward-wound mesh without degenerate triangles (MeshCheck::ok(); with
/// params.remove_cavities off, bubbles' walls are kept, wound inward: ok_allowing_cavities()), possibly empty when
/// the particles are too sparse to make a surface (every component smaller than min_component_volume, or φ never
/// reaches iso; see stats->max_field).
/// Errors: Input for no particles or a non-finite coordinate (naming the first such particle); Param for a
/// spacing that is not finite and > 0, invalid params or a cloud too large for the grid; Numerical if the
/// extraction (marching cubes or tetrahedra) itself fails the mesh check (an internal error).
/// max_memory_mib bounds the field grid's memory (sparse_field; 0: 80 % of the machine's).
Result<io::TriangleMesh> reconstruct(std::span<const Vec3f> particles, float spacing, const SurfaceParams& params,
                                     SurfaceStats* stats = nullptr, double max_memory_mib = 0.0);

}  // namespace ff::surface
