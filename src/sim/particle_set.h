#pragma once
// The fluid particles, structure of arrays with ONE field list: resize, reorder,
// checkpoint and validation all iterate `for_each_array`, so adding a field is one line.
#include "core/types.h"

#include <cstdint>
#include <span>
#include <vector>

namespace ff::sim {

/// Target id of a particle that belongs to no target (exported as `uchar target`).
inline constexpr std::uint8_t kFreeFluid = 255;

struct ParticleSet {
  // State carried from step to step (reordered with the particles and checkpointed).
  std::vector<Vec3f> position;        ///< x, metres
  std::vector<Vec3f> velocity;        ///< v, m/s
  std::vector<Index> bound_control;   ///< control particle bound to (flattened index) or kInvalidIndex
  std::vector<std::uint8_t> target;   ///< target id, kFreeFluid for none
  std::vector<Index> id;              ///< stable id: exports and metrics key on it, survives reordering
  // Per-step values, recomputed every sub-step (not reordered, not checkpointed).
  std::vector<Vec3f> acceleration;    ///< a_ext of the last sub-step, m/s²
  std::vector<Vec3f> predicted;       ///< x*, metres
  std::vector<float> density;         ///< ρ at the start of the last sub-step, kg/m³
  std::vector<float> lambda;          ///< PBF Lagrange multiplier of the last iteration, m²
  /// Displacement a controller applied to x* this sub-step that must not become velocity (kinematic
  /// control, see control/adaptive_params.h): v = (x* − x − shift)/Δt. Zeroed by the solver every sub-step.
  std::vector<Vec3f> shift;

  std::size_t size() const { return position.size(); }

  /// The persistent fields: what defines the simulation state.
  template <class F>
  void for_each_state_array(F&& f) {
    f(position); f(velocity); f(bound_control); f(target); f(id);
  }
  template <class F>
  void for_each_state_array(F&& f) const {
    f(position); f(velocity); f(bound_control); f(target); f(id);
  }
  /// Every field, state first.
  template <class F>
  void for_each_array(F&& f) {
    for_each_state_array(f);
    f(acceleration); f(predicted); f(density); f(lambda); f(shift);
  }
  template <class F>
  void for_each_array(F&& f) const {
    for_each_state_array(f);
    f(acceleration); f(predicted); f(density); f(lambda); f(shift);
  }

  /// Appends a particle with the given position and velocity; its id is its current count.
  void push_back(const Vec3f& x, const Vec3f& v, std::uint8_t target_id = kFreeFluid);
  /// Resizes every array (new entries zero / invalid).
  void resize(std::size_t n);
  /// True when every array has size() entries.
  bool consistent() const;
  /// Bytes held by the arrays (capacity).
  std::size_t bytes() const;
};

/// Scratch buffers for reorder(), one per element type, reused between calls.
struct ReorderScratch {
  std::vector<Vec3f> v3;
  std::vector<float> f32;
  std::vector<Index> u32;
  std::vector<std::uint8_t> u8;
};

/// Permutes the state arrays: new[i] = old[perm[i]]. Per-step arrays are only resized.
void reorder(ParticleSet& p, std::span<const Index> perm, ReorderScratch& scratch);

/// Particles sorted by id (export order), as positions/velocities/targets copies.
void sorted_by_id(const ParticleSet& p, std::vector<Vec3f>& x, std::vector<Vec3f>& v, std::vector<std::uint8_t>& t);

}  // namespace ff::sim
