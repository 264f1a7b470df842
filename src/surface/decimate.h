#pragma once
// Decimation with meshoptimizer's edge-collapse simplifier (meshopt_simplify: quadric error, avoids triangle
// flips). It does not test the link condition, so a collapse can pinch the surface into a non-manifold edge
// (measured: on a 113k-particle sphere nearly every pass leaves 1–4 such edges). Every pass is therefore
// checked; where it broke the mesh, the vertices there and two rings around them are locked and the pass is
// redone; a pass that cannot be made clean is dropped, keeping the last good mesh.
//
// Two phases: (1) collapse while the error stays under `max_error` (light meshes where the surface is simple);
// (2) while over the triangle budget, halve the count per pass whatever the error (so that a failing pass
// costs only its own half, not the whole budget).
#include "io/triangle_mesh.h"
#include "surface/mesh_check.h"

#include <cstddef>

namespace ff::surface {

struct DecimateParams {
  float max_error = 0.0f;         ///< phase 1 error bound, m (0: skip phase 1)
  std::size_t max_triangles = 0;  ///< phase 2 budget (0: no budget)
  bool allow_cavities = false;    ///< judge passes by MeshCheck::ok_allowing_cavities() instead of ok()
};

struct DecimateStats {
  std::size_t passes = 0;           ///< simplifier passes kept
  std::size_t rejected_passes = 0;  ///< simplifier runs whose result was broken and thrown away (then redone)
  float error = 0.0f;               ///< meshoptimizer's error of the kept result (m, summed over passes: a bound)
  bool budget_met = true;
};

/// The decimated mesh; `mesh` must pass check_mesh(). Unused vertices are dropped, the vertex order otherwise
/// kept. Deterministic (meshoptimizer is single-threaded).
io::TriangleMesh decimate(const io::TriangleMesh& mesh, const DecimateParams& params, DecimateStats* stats = nullptr);

/// Vertex colours for `to`, a decimated copy of `from` (decimation moves and merges vertices): each vertex the colour of
/// the nearest vertex of `from`. Nothing when `from` has none.
void carry_colours(const io::TriangleMesh& from, io::TriangleMesh& to);

}  // namespace ff::surface
