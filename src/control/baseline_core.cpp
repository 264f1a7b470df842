#include "control/baseline_core.h"

#include "core/parallel.h"

#include <cmath>

namespace ff::control {

Status BaselineCore::init(std::vector<ControlTarget> targets, const ControlContext& c, std::string_view who) {
  ctx = c;
  d = ctx.spacing();
  FF_CHECK(samples.init(std::move(targets), who, {.cell_order = false, .weights = true, .normals = false, .velocities = true}));
  hc = samples.hc;
  live.assign(samples.targets(), 0);
  // The grids' cells are the largest radius any baseline queries (its own radius may be smaller).
  fluid_grid_ = core::NeighborGrid(2.0f * hc);
  sample_grid_ = core::NeighborGrid(2.0f * hc);
  return {};
}

bool BaselineCore::update(double t_now, float dt) {
  time = t_now;
  for (std::size_t t = 0; t < live.size(); ++t) live[t] = samples.acting(static_cast<std::uint8_t>(t), t_now) ? 1 : 0;
  const bool swapped = samples.update(t_now, dt);
  if (swapped || samples.moving()) sample_grid_valid_ = false;
  return swapped;
}

void BaselineCore::set_target_pose(std::size_t t, const pose::Pose& pose) { samples.set_target_pose(t, pose); }

void BaselineCore::sample_to_fluid(const sim::ParticleSet& p, float r) {
  fluid_grid_.build(p.position);
  fluid_grid_.query(p.position, samples.position, r, near_fluid);
}

void BaselineCore::fluid_to_sample(const sim::ParticleSet& p, float r) {
  if (!sample_grid_valid_) sample_grid_.build(samples.position), sample_grid_valid_ = true;
  sample_grid_.query(samples.position, p.position, r, near_samples);
}

}  // namespace ff::control
