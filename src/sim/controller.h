#pragma once
// The hook interface the PBF step calls. It lives with the solver that calls it;
// control/ implements it, so sim never includes control. Virtual at step granularity, never per particle.
#include "core/neighbor_grid.h"
#include "sim/particle_set.h"

#include <string_view>

namespace ff::sim {

/// Read-only view of the current sub-step. Valid only during a hook call.
struct StepView {
  float dt = 0.0f;           ///< s, current sub-step
  double time = 0.0;         ///< s, start of this sub-step
  int iteration = -1;        ///< density-constraint iteration (correct_positions only)
  int iterations = 0;        ///< N_it, the nominal iteration count (more may run while the density error is high)
  float particle_radius = 0.0f;  ///< r, m
  const core::NeighborList* fluid_neighbors = nullptr;  ///< built this sub-step on `position`
};

/// A shape-control method. Per sub-step the solver calls, in this order (METHOD.md §a.6):
///   begin_step → add_accelerations → [predict x*] → N × { correct_positions; PBF iteration; walls } → end_step
///   → emit
/// Hooks may write only: acceleration, predicted, shift (the part of a correction that is not to become
/// velocity), bound_control. Only emit may add particles (ParticleSet::push_back, between sub-steps: the next
/// sub-step sizes every array and searches again); particles are never removed.
class Controller {
 public:
  virtual ~Controller() = default;
  virtual std::string_view name() const = 0;
  virtual void begin_step(const StepView&, ParticleSet&) {}
  virtual void add_accelerations(const StepView&, ParticleSet&) {}  ///< m/s², added in place
  virtual void correct_positions(const StepView&, ParticleSet&) {}  ///< metres, added to `predicted`
  virtual void end_step(const StepView&, const ParticleSet&) {}
  virtual void emit(const StepView&, ParticleSet&) {}  ///< may append particles (LCAT's temporaries)
};

/// Plain PBF: no control (the `none` entry of the controller registry builds on this).
class NoController final : public Controller {
 public:
  std::string_view name() const override { return "none"; }
};

}  // namespace ff::sim
