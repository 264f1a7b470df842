#pragma once
// Parameters of the paper's controller, `adaptive` (METHOD.md §a.2–§a.6, defaults of §a.9 and §a.10).
// Every component can be switched off or set to its literal paper reading, so its contribution can be
// measured (the ablations of bench/RESULTS.md). JSON keys in scene files ("controller": {"adaptive": {...}}) are the
// field names; enums are strings.
#include "control/controller_info.h"
#include "core/error.h"
#include "core/fields.h"

#include <array>
#include <cstdint>
#include <optional>
#include <string_view>
#include <vector>

namespace ff::control {

/// Bond radius rule of eq. 19 (METHOD §a.5).
enum class BondRadius {
  OverFull,  ///< H_c* = H_c · min(1, 2ρ_c/(ρ_p + ρ_c)): shrinks only once a sample is over-full (default, §a.10)
  Paper,     ///< H_c* = H_c · ρ_c/(ρ_p + ρ_c): the literal reading (halves the radius of every filled sample)
};
constexpr std::array<core::Choice<BondRadius>, 2> field_choices(BondRadius) {
  return {{{BondRadius::OverFull, "over-full"}, {BondRadius::Paper, "paper"}}};
}
std::string_view bond_radius_name(BondRadius b);
std::optional<BondRadius> parse_bond_radius(std::string_view s);

/// The sub-step the clamp and the spring strength refer to (METHOD §0: Δt = 1/120 s).
inline constexpr float kReferenceDt = 1.0f / 120.0f;

struct AdaptiveParams {
  static constexpr ControllerInfo info{"adaptive", "the paper (Zhou et al.): adaptive weights, unilateral density control, bond breaking, boundary correction", false};
  bool weights = true;              ///< eq. 1–5: scale each sample's correction by φ̃; off → φ̃ = 1
  bool boundary_correction = true;  ///< eq. 15–16: remove the outward part of a_ext at the target surface
  bool bond_breaking = true;        ///< eq. 17–19: adaptive bond radius and soft spring; off → every pair within H_c is bonded, no spring
  BondRadius bond_radius = BondRadius::OverFull;
  bool gather = true;               ///< ours (§a.10): unbonded fluid is steered toward under-filled samples of its target
  /// Kinematic control: the control correction and the spring move fluid without becoming velocity (an option
  /// to measure). Off (default, the PBD reading): corrections become velocity like every constraint's, which is
  /// what lets the control hold fluid up against gravity; kinematic control cannot cancel the velocity gravity
  /// builds, and on the bunny the fluid fell through the target (E 5.5 %, 64 % inside, 32 % splash).
  bool kinematic = false;
  /// Speed limit of controlled fluid, in spacings d per second (ours): in the PBD reading an empty sample
  /// accelerates its fluid at up to clamp · N_it · d / Δt² (≈ 17 g at the defaults) until it is full, the fluid
  /// overshoots, and the CFL rule shrinks Δt without end (measured: 60 m/s after 5 frames). Limiting the speed
  /// of bonded particles to the clamp's own inflow speed, clamp · N_it · d / Δt_ref = 48 d/s, keeps the
  /// inflow the clamp sets (METHOD §a.3) and nothing faster. (0, 10000]
  float max_speed = 48.0f;
  /// Moving targets (keyframes, skins, live steering; ours): bonded fluid follows the pose velocity u_c of its nearest
  /// bonded sample (the paper's v_c). Each sub-step at Δt_ref this share of the difference v − u_c is removed, and
  /// the speed limit above holds for v − u_c instead of v. Without it the fluid can only be pulled along at the
  /// clamp's inflow speed (48 d/s, ~1 m/s on the 10k character) and a walking character's feet and hands, at 2–3 m/s,
  /// shed their fluid. Static targets (u_c = 0) are not affected. [0, 1]; 0 = off.
  float follow = 0.25f;

  float alpha = 0.5f;               ///< α of eq. 5/10, strength of the control correction. (0, 2]
  float epsilon = 1.0f;             ///< ε_c of eq. 6 as a multiple of S_0 (Σ|g|² of a full neighbourhood). (0, 100]
  /// Largest control correction per fluid particle and iteration, in spacings d, at the reference sub-step
  /// Δt_ref = 1/120 s (METHOD §0); (0, 1]. A position correction of fixed size becomes a faster velocity as Δt
  /// shrinks, and a faster velocity makes the CFL rule shrink Δt again: so the clamp (and the spring) are
  /// scaled by Δt/Δt_ref, which keeps the inflow speed clamp · N_it · d / Δt_ref (48 d/s) whatever Δt is.
  float clamp = 0.1f;
  float gamma = 0.1f;               ///< γ_a of the adaptive spring (eq. 18 as §a.5), once per sub-step, at Δt_ref. [0, 1]
  float normal_threshold = 0.25f;   ///< boundary correction only where |n| ≥ this × g_ref (eq. 15). [0, 1]
  float gather_fill = 0.9f;         ///< a sample is under-filled while ρ_p/ρ_c < this. (0, 1]
  float gather_speed = 20.0f;       ///< speed unbonded fluid is steered at, in spacings d per second. (0, 1000]
  float gather_time = 0.1f;         ///< s, time constant with which the steering velocity is reached. (0, 10]
  /// On a moving target unbonded fluid is steered at the seed's pose velocity u_c plus an approach toward it of at
  /// least this share of |u_c| (and at least gather_speed). Ours. With the approach at gather_speed alone (2.3 m/s
  /// on huesitos.fbx, whose limbs move at up to 32 m/s) the fluid a fast limb shed chased it for the whole run: up
  /// to 30 % of the fluid outside from 4 to 14 s; at 1, 99.34 % or more inside from 1 s on (bench/RESULTS.md,
  /// "seventh part"). Static targets (u_c = 0) are not affected, nor is anything with follow = 0 (no chase at all).
  /// [0, 10]; 0 = the approach at gather_speed only.
  float gather_chase = 1.0f;
  /// The count of control samples per target the three speeds above (clamp, max_speed, gather_speed, all in spacings
  /// per second) were set at (ours, issue 44). A target of N_t samples runs them × max(1, (N_t / this)^(1/3)): the
  /// same speeds in target sizes per second at any resolution, so a finer target forms in the same simulated time
  /// and its fluid is not held back at a speed a 10k target needed. The factor is about the ratio of the spacing at
  /// the reference count to the target's own. Measured: the 100k bunny at × 1 formed at 5.4 s and let ~3 % go once
  /// the sub-steps grew; by this rule (× 2.03) it formed at 2.63 s, 1.35× the 10k bunny's 1.95 s, and held to 25 s
  /// (bench/RESULTS.md, "Detail at scale, seventh part"). The clamp stays at most one spacing per iteration.
  /// [0, 1e9]; 0 = the speeds as written at every count.
  float speed_reference = 12000.0f;

  template <class S, class F>
  static void fields(S& s, F&& f) {
    using namespace core;
    f("weights", s.weights, plain("eq. 1–5: scale each sample's correction by φ̃"));
    f("boundary_correction", s.boundary_correction, plain("eq. 15–16: remove the outward part of a_ext at the surface"));
    f("bond_breaking", s.bond_breaking, plain("eq. 17–19: adaptive bond radius and soft spring"));
    f("bond_radius", s.bond_radius, plain("H_c*: shrinks once over-full (over-full) or the literal eq. 19 (paper)"));
    f("gather", s.gather, plain("ours: unbonded fluid is steered toward under-filled samples"));
    f("kinematic", s.kinematic, plain("corrections move fluid without becoming velocity (an option to measure)"));
    f("max_speed", s.max_speed, open_closed(0.0, 10000.0, "speed limit of controlled fluid, d/s"));
    f("follow", s.follow, closed(0.0, 1.0, "moving targets: share of v − u_c removed per sub-step at Δt_ref"));
    f("alpha", s.alpha, open_closed(0.0, 2.0, "α of eq. 5/10, strength of the control correction"));
    f("epsilon", s.epsilon, open_closed(0.0, 100.0, "ε_c of eq. 6, × S_0"));
    f("clamp", s.clamp, open_closed(0.0, 1.0, "largest correction per particle and iteration, d, at Δt_ref"));
    f("gamma", s.gamma, closed(0.0, 1.0, "γ_a of the adaptive spring (eq. 18), at Δt_ref"));
    f("normal_threshold", s.normal_threshold, closed(0.0, 1.0, "boundary correction only where |n| ≥ this × g_ref"));
    f("gather_fill", s.gather_fill, open_closed(0.0, 1.0, "a sample is under-filled while ρ_p/ρ_c < this"));
    f("gather_speed", s.gather_speed, open_closed(0.0, 1000.0, "steering speed of unbonded fluid, d/s"));
    f("gather_time", s.gather_time, open_closed(0.0, 10.0, "s, time constant of the steering"));
    f("gather_chase", s.gather_chase, closed(0.0, 10.0, "moving targets: least approach speed toward a seed, × its |u_c|"));
    f("speed_reference", s.speed_reference,
      closed(0.0, 1e9, "samples per target the speeds are set at: clamp, max_speed, gather_speed × max(1, (N_t/this)^⅓); 0 = off"));
  }
  /// First violation, naming `path.key`, the value and the range.
  Status validate(std::string_view path = "controller.adaptive") const { return core::validate_fields(*this, path); }
};

/// Per target, the factor its speeds run at (AdaptiveParams::speed_reference): max(1, (N_t / reference)^(1/3)) with
/// N_t its count in `target` (each sample's target); 1 everywhere when reference is 0.
std::vector<float> speed_scales(const std::vector<std::uint8_t>& target, std::size_t targets, float reference);

}  // namespace ff::control
