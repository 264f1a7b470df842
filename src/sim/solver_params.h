#pragma once
// Parameters of the PBF solver, the domain and the fluid sources (METHOD.md §0, §c.2), with
// documented defaults, units and ranges. JSON keys in scene files are the field names.
#include "core/error.h"
#include "core/fields.h"
#include "core/types.h"

#include <array>

#include <string_view>
#include <vector>

namespace ff::sim {

struct SolverParams {
  /// r, m; spacing d = 2r. (1e-4, 1e4]: wide above, because targets come in any unit (a character exported in centimetres
  /// is hundreds of "metres" tall); what a radius costs is checked against the target (the run's budget).
  float particle_radius = 0.025f;
  float support_factor = 4.0f;     ///< H_p = support_factor · r (METHOD: 4r = 2d). [2.5, 8]
  int iterations = 4;              ///< density-constraint iterations per sub-step (minimum). [1, 100]
  int max_iterations = 30;         ///< more iterations while the mean density error exceeds max_density_error.
                                   ///< [iterations, 1000]; = iterations for a fixed count (benchmarks)
  float max_density_error = 0.005f;  ///< target mean compression max(ρ/ρ0 − 1, 0) (0.5 %). (0, 1]
  float max_dt = 1.0f / 120.0f;    ///< largest sub-step, s (METHOD §0: 1/120). (0, 0.1]
  float cfl = 0.4f;                ///< largest displacement per sub-step, in spacings d. (0, 1]
  /// Capillary time-step condition (Brackbill et al. 1992; Morris 2000 for SPH): Δt ≤ capillary_cfl ·
  /// √(ρ0 H_p³ / (2π σ_eff)), σ_eff = surface_tension / d_ref² the surface tension as a pressure jump per curvature
  /// (see kSurfaceTensionRefSpacing). Explicit surface tension is stable only below it, and it shrinks as d^1.5,
  /// faster than the CFL sub-step: without it the 100k bunny, formed, let 3 % of its fluid go once the CFL rule
  /// allowed 3 sub-steps a frame (bench/RESULTS.md, "Detail at scale"). 0 = off. [0, 10]
  float capillary_cfl = 0.4f;
  int max_substeps = 64;           ///< cap on sub-steps per output frame. [1, 10000]
  Vec3f gravity{0.0f, -10.0f, 0.0f};  ///< m/s² (paper: (0, −10, 0)). components in [−1000, 1000]
  float rest_density = 1000.0f;    ///< physical ρ0, kg/m³; the solver calibrates to the lattice sum. (0, 1e5]
  float viscosity = 0.01f;         ///< XSPH η (paper eq. 12, acceleration form). [0, 1]
  float vorticity = 0.0f;          ///< vorticity confinement ε_v, m/s (off by default for shape control). [0, 10]
  float epsilon = 0.01f;           ///< λ relaxation ε as a multiple of S_0 (Σ|∇C|² at rest). (0, 100]
  float scorr_k = 0.1f;            ///< tensile-instability strength k (s_corr / S_0). [0, 1]
  int scorr_n = 4;                 ///< s_corr exponent n. [1, 8]
  float scorr_dq = 0.2f;           ///< |Δq| as a multiple of H_p. (0, 1)
  // External forces of the seed paper (METHOD.md §a.4 eq. 13–14), added after XSPH (sim/surface_tension.h, sim/drag.h).
  float surface_tension = 0.05f;   ///< σ of Zorilla et al.: a = −(σ/m) κ n̂ on surface particles, at the reference
                                   ///< spacing 0.05 m, scaled by (d/0.05)² (pbf_solver.cpp says why); 0 = off. [0, 10]
                                   ///< A force σκ per particle (no area factor): σ/m ∝ 1/d³ (sim/surface_tension.h).
  float surface_tension_samples = 10000.0f;  ///< C_sd, Monte-Carlo points per second: N = ⌊C_sd·Δt⌋ (≥ 1) per
                                             ///< surface particle and sub-step (83 at Δt = 1/120 s). [1, 1e6];
                                             ///< large N destabilises fine spacings (sim/surface_tension.h)
  float drag = 0.01f;              ///< s, Gissler et al. drag scale: a = s·½ρ_a‖v_rel‖v_rel C_D A/m; 0 = off. [0, 10]
  float air_density = 1.2931f;     ///< ρ_a, kg/m³ (seed value). (0, 100]

  float spacing() const { return 2.0f * particle_radius; }
  float support() const { return support_factor * particle_radius; }
  /// σ is given at this spacing (SPlisHSPlasH's default radius, where the paper's σ = 0.05 comes from) and scaled by
  /// (d/d_ref)² per particle, so the pressure jump σκ/d_ref² does not depend on the resolution.
  static constexpr float kSurfaceTensionRefSpacing = 0.05f;
  /// The capillary condition's largest sub-step, s (+∞ without surface tension or with the condition off).
  double capillary_dt() const;

  /// The one list of the fields (core/fields.h): validation, the scene reader and writer, the key table.
  template <class S, class F>
  static void fields(S& s, F&& f) {
    using namespace core;
    f("particle_radius", s.particle_radius, open_closed(1e-4, 1e4, "r, m; spacing d = 2r (default: from the targets)"));
    f("support_factor", s.support_factor, closed(2.5, 8.0, "H_p = support_factor · r"));
    f("iterations", s.iterations, closed(1, 100, "density-constraint iterations per sub-step (minimum)"));
    f("max_iterations", s.max_iterations, closed(1, 1000, "more iterations while the density error is high; ≥ iterations"));
    f("max_density_error", s.max_density_error, open_closed(0.0, 1.0, "target mean compression max(ρ/ρ0 − 1, 0)"));
    f("max_dt", s.max_dt, open_closed(0.0, 0.1, "largest sub-step, s"));
    f("cfl", s.cfl, open_closed(0.0, 1.0, "largest displacement per sub-step, in spacings d"));
    f("capillary_cfl", s.capillary_cfl, closed(0.0, 10.0, "capillary time-step condition: Δt ≤ this · √(ρ0 H_p³/(2π σ)); 0 = off"));
    f("max_substeps", s.max_substeps, closed(1, 10000, "cap on sub-steps per output frame"));
    f("gravity", s.gravity, closed(-1000.0, 1000.0, "m/s², each component"));
    f("rest_density", s.rest_density, open_closed(0.0, 1e5, "physical ρ0, kg/m³"));
    f("viscosity", s.viscosity, closed(0.0, 1.0, "XSPH η (paper eq. 12)"));
    f("vorticity", s.vorticity, closed(0.0, 10.0, "vorticity confinement ε_v, m/s"));
    f("epsilon", s.epsilon, open_closed(0.0, 100.0, "λ relaxation ε, × S_0"));
    f("scorr_k", s.scorr_k, closed(0.0, 1.0, "tensile-instability strength k"));
    f("scorr_n", s.scorr_n, closed(1, 8, "s_corr exponent n"));
    f("scorr_dq", s.scorr_dq, open(0.0, 1.0, "Δq as a length, × H_p"));
    f("surface_tension", s.surface_tension, closed(0.0, 10.0, "σ (seed eq. 13) at the reference spacing 0.05 m; 0 = off"));
    f("surface_tension_samples", s.surface_tension_samples, closed(1.0, 1e6, "C_sd, Monte-Carlo points per second"));
    f("drag", s.drag, closed(0.0, 10.0, "s, air drag scale (seed eq. 14); 0 = off"));
    f("air_density", s.air_density, open_closed(0.0, 100.0, "ρ_a, kg/m³"));
  }
  /// First violation, naming `path.key`, the value and the range.
  Status validate(std::string_view path = "solver") const;
};

/// The box the fluid lives in; walls clamp particle centres to [min + r, max − r].
struct Domain {
  Vec3f min{-1.0f, 0.0f, -1.0f};  ///< m
  Vec3f max{1.0f, 2.0f, 1.0f};    ///< m; each component > min by at least 4r
  template <class S, class F>
  static void fields(S& s, F&& f) {
    f("min", s.min, core::closed(-1e6, 1e6, "m, the lower corner (default: the targets and the fluid with a margin)"));
    f("max", s.max, core::closed(-1e6, 1e6, "m, the upper corner; at least 4r above min on every axis"));
  }
  Status validate(float particle_radius, std::string_view path = "domain") const;
};

/// A fluid source filled on the cubic lattice of spacing d at the start of the run.
struct FluidSource {
  enum class Shape { Box, Sphere };
  friend constexpr std::array<core::Choice<Shape>, 2> field_choices(Shape) { return {{{Shape::Box, "box"}, {Shape::Sphere, "sphere"}}}; }
  Shape shape = Shape::Box;
  Vec3f min{Vec3f::Zero()}, max{Vec3f::Zero()};  ///< box corners, m
  Vec3f center{Vec3f::Zero()};                   ///< sphere centre, m
  float radius = 0.0f;                           ///< sphere radius, m, > 0
  Vec3f velocity{Vec3f::Zero()};                 ///< initial velocity, m/s
  template <class S, class F>
  static void fields(S& s, F&& f) {
    f("shape", s.shape, core::plain("box or sphere"));
    f("min", s.min, core::plain("m, a box's lower corner (box: required)"));
    f("max", s.max, core::plain("m, a box's upper corner (box: required)"));
    f("center", s.center, core::plain("m, a sphere's centre (sphere: required)"));
    f("radius", s.radius, core::plain("m, a sphere's radius, > 0 (sphere: required)"));
    f("velocity", s.velocity, core::closed(-1e4, 1e4, "m/s, initial velocity"));
  }
  /// The fields a shape needs ("box": min, max; "sphere": center, radius).
  static std::array<std::string_view, 2> required_for(Shape shape) {
    return shape == Shape::Box ? std::array<std::string_view, 2>{"min", "max"} : std::array<std::string_view, 2>{"center", "radius"};
  }
  Status validate(std::string_view path) const;
};

}  // namespace ff::sim
