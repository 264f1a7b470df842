#pragma once
// Parameters of surface reconstruction (METHOD.md §a.7, §c.8, §c.9). Every length is relative to the particle
// spacing d (the rest distance between fluid particles), so the defaults need no tuning across scene scales.
#include "core/error.h"
#include "core/fields.h"

#include <array>

#include <cstddef>
#include <string_view>

namespace ff::surface {

/// How the iso-surface φ = iso is extracted from the grid (METHOD.md §c.8, §c.9). Both give a welded, closed mesh
/// whose vertices record their nearest grid node, so the same `reduction` and later stages follow either.
enum class Extraction {
  MarchingCubes,  ///< marching cubes, ambiguous faces by the asymptotic decider (marching_cubes.h; default)
  /// Marching tetrahedra, 6 Kuhn tetrahedra per cube (marching_tetrahedra.h). With Reduction::Cluster (the
  /// default) this is Treece, Prager & Gee's regularised marching tetrahedra, RMT; with Reduction::None, plain
  /// marching tetrahedra (about twice marching cubes' triangles, many of them slivers).
  MarchingTetrahedra,
};

constexpr std::array<core::Choice<Extraction>, 2> field_choices(Extraction) {
  return {{{Extraction::MarchingCubes, "mc"}, {Extraction::MarchingTetrahedra, "rmt"}}};
}

/// The command line's name of an extraction: "mc" or "rmt" (which also names plain marching tetrahedra when the
/// reduction is off).
std::string_view extraction_name(Extraction e);
/// "mc" or "rmt"; otherwise a Param error that quotes `name` and names the accepted values.
Result<Extraction> parse_extraction(std::string_view name);

/// How the extracted vertices are reduced before decimation (METHOD.md §a.7 "Reduction", §c.9).
enum class Reduction {
  None,     ///< keep every extracted vertex
  Cluster,  ///< regularisation of Treece et al.: vertices nearest to one grid node merge (default)
};

constexpr std::array<core::Choice<Reduction>, 2> field_choices(Reduction) {
  return {{{Reduction::None, "none"}, {Reduction::Cluster, "cluster"}}};
}

struct SurfaceParams {
  // --- scalar field φ(x) = Σ_p V_p W_poly6(x − x_p, h) (METHOD §a.7 [D]) ------------------------------------
  float cell_size = 0.5f;        ///< grid cell edge, × d. METHOD §a.7: d/2. [0.05, 4]
  float kernel_radius = 2.0f;    ///< h of W_poly6, × d; at most 8 cells (one block of the sparse grid). [0.5, 8]
  float particle_volume = 1.0f;  ///< V_p = m_p/ρ_p, × d³ (a fluid at rest has one particle per d³). (0, 10]
  float iso = 0.5f;              ///< iso value of φ (≈ 1 inside, 0 outside). (0, 1)

  // --- weighted vertex smoothing, paper eq. 20–21 (METHOD §a.7) -----------------------------------------------
  int smoothing_passes = 2;       ///< passes of V' = V + β ΔV. [0, 100]
  float smoothing_beta = 0.5f;    ///< β of eq. 20. [0, 1]
  float smoothing_radius = 2.0f;  ///< H_v of eq. 21, × cell (METHOD: 2 cells). [0.5, 8]
  /// μ of a Taubin back-step after each pass (smooth.h); 0 gives the paper's plain eq. 20. Measured on a
  /// lattice-filled bunny: the farthest target point from the mesh is 1.20 d away without smoothing, 1.23 d with
  /// two passes at μ = 0.53 and 1.36 d with the plain passes (which shrink ears and tips). [0, 1]
  float smoothing_inflate = 0.53f;

  // --- extraction and vertex reduction (METHOD §a.7, §c.8, §c.9) --------------------------------------------------
  /// Marching cubes by default (the meshes of earlier versions, bit for bit). MarchingTetrahedra (+ the default
  /// Cluster reduction) is RMT. Measured on the analytic sphere and torus (tests/surface/rmt_test.cpp), before
  /// smoothing and decimation: plain marching tetrahedra make ~2.9× marching cubes' triangles; RMT keeps ~0.26 of
  /// them (0.74–0.76 of marching cubes', where cluster-reduced marching cubes keeps 0.52–0.55), with no merge
  /// undone, at the same distance to the true surface.
  Extraction extraction = Extraction::MarchingCubes;
  Reduction reduction = Reduction::Cluster;

  // --- decimation with meshoptimizer ----------------------------------------------------------------------------
  /// Collapse edges while meshoptimizer's error stays below this, × d (0: no error-driven decimation). Measured
  /// (tests/surface): after the reduction, 0.02 d leaves 30–36 % of plain marching cubes' triangles on the
  /// analytic sphere and torus and 35 % on a lattice-filled bunny, with the symmetric distance to the true
  /// surface unchanged to within 0.002 d (mean) and 0.01 d (worst); the field itself is off by up to ~0.4 d.
  /// [0, 10]
  float decimate_error = 0.02f;
  /// Triangle budget: decimate further, whatever the error, until at most this many remain (0: no budget).
  /// 20k keeps a mesh light enough to edit and auto-rig. [0, 1e9]
  std::size_t max_triangles = 20'000;

  // --- clean-up -------------------------------------------------------------------------------------------------
  /// Connected components enclosing less than this volume, × d³, are dropped (spray droplets). A lone particle
  /// makes no surface at the defaults (φ peaks at ≈ 0.2 < iso); ~27 particles (a 3³ clump) make a blob that is
  /// kept. [0, 1e9]
  float min_component_volume = 8.0f;
  /// Drop closed components that enclose air (negative signed volume: bubbles inside the fluid). They are
  /// invisible from outside and would give an editable mesh hidden inner walls (auto-rigging's inside test and
  /// sculpting both trip on them).
  bool remove_cavities = true;

  /// Refuse grids needing more than this many 8³-node blocks (memory guard: ~3 kB per block near the surface,
  /// 8 bytes per block elsewhere). [1, 1e9]
  std::size_t max_blocks = 50'000'000;

  template <class S, class F>
  static void fields(S& s, F&& f) {
    using namespace core;
    f("cell_size", s.cell_size, closed(0.05, 4.0, "grid cell edge, × d"));
    f("kernel_radius", s.kernel_radius, closed(0.5, 8.0, "h of W_poly6, × d; at most 8 cells"));
    f("particle_volume", s.particle_volume, open_closed(0.0, 10.0, "V_p, × d³"));
    f("iso", s.iso, open(0.0, 1.0, "iso value of φ"));
    f("smoothing_passes", s.smoothing_passes, closed(0, 100, "passes of eq. 20"));
    f("smoothing_beta", s.smoothing_beta, closed(0.0, 1.0, "β of eq. 20"));
    f("smoothing_radius", s.smoothing_radius, closed(0.5, 8.0, "H_v of eq. 21, × cell"));
    f("smoothing_inflate", s.smoothing_inflate, closed(0.0, 1.0, "μ of a Taubin back-step after each pass (0: plain eq. 20)"));
    f("extraction", s.extraction, plain("marching cubes (mc) or regularised marching tetrahedra (rmt)"));
    f("reduction", s.reduction, plain("vertices nearest to one grid node merge (cluster) or not (none)"));
    f("decimate_error", s.decimate_error, closed(0.0, 10.0, "meshoptimizer's error bound, × d (0: none)"));
    f("max_triangles", s.max_triangles, closed(0, 1e9, "triangle budget (0: none)"));
    f("min_component_volume", s.min_component_volume, closed(0.0, 1e9, "drop components smaller than this, × d³"));
    f("remove_cavities", s.remove_cavities, plain("drop closed components that enclose air"));
    f("max_blocks", s.max_blocks, closed(1, 1e9, "refuse grids needing more 8³-node blocks than this"));
  }
  Status validate(std::string_view path = "surface") const;
};

}  // namespace ff::surface
