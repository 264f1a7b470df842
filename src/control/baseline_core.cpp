#include "control/baseline_core.h"

#include "core/parallel.h"

#include <cmath>

namespace ff::control {

Status BaselineCore::init(std::vector<ControlTarget> targets, const ControlContext& c, std::string_view who) {
  ctx = c;
  d = ctx.spacing();
  FF_TRY(CheckedTargets checked, check_targets(std::move(targets), who));
  hc = checked.hc;
  phases_ = std::move(checked.phases);
  start_ = std::move(checked.start);
  motion_ = std::move(checked.motion);
  moving_ = checked.moving;
  current_.assign(phases_.size(), 0);
  live.assign(phases_.size(), 0);
  // The grids' cells are the largest radius any baseline queries (its own radius may be smaller).
  fluid_grid_ = core::NeighborGrid(2.0f * hc);
  sample_grid_ = core::NeighborGrid(2.0f * hc);
  flatten();
  return {};
}

void BaselineCore::flatten() {
  xc.clear(), rho_c.clear(), tc.clear(), mass_c.clear();
  for (std::size_t t = 0; t < phases_.size(); ++t) {
    const auto& s = phases_[t][current_[t]].set;
    mass_c.push_back(s.mass);
    xc.insert(xc.end(), s.position.begin(), s.position.end());
    rho_c.insert(rho_c.end(), s.density.begin(), s.density.end());
    tc.insert(tc.end(), s.size(), static_cast<std::uint8_t>(t));
  }
  rest_ = xc;
  uc.assign(xc.size(), Vec3f::Zero());
  sample_grid_valid_ = false;
}

bool BaselineCore::update(double t_now, float dt) {
  time = t_now;
  for (std::size_t t = 0; t < phases_.size(); ++t) live[t] = t_now >= start_[t] ? 1 : 0;
  bool swapped = false;
  for (std::size_t t = 0; t < phases_.size(); ++t)
    while (current_[t] + 1 < phases_[t].size() && t_now >= phases_[t][current_[t] + 1].time) ++current_[t], swapped = true;
  if (swapped) flatten();
  if (!moving_) return swapped;
  // u_c is the pose's velocity over this sub-step (forward difference), so a rig that moves drags its fluid along.
  std::vector<Pose> now(motion_.size()), next(motion_.size());
  for (std::size_t t = 0; t < motion_.size(); ++t) now[t] = motion_[t].at(t_now), next[t] = motion_[t].at(t_now + dt);
  const float inv_dt = dt > 0.0f ? 1.0f / dt : 0.0f;
  core::parallel_for(static_cast<std::int64_t>(xc.size()), [&](std::int64_t ii) {
    const auto i = static_cast<std::size_t>(ii);
    const auto t = tc[i];
    if (!motion_[t].moving()) return;
    xc[i] = now[t].apply(rest_[i]);
    uc[i] = (next[t].apply(rest_[i]) - xc[i]) * inv_dt;
  });
  sample_grid_valid_ = false;
  return swapped;
}

void BaselineCore::set_target_pose(std::size_t t, const Pose& pose) {
  if (t >= motion_.size()) return;
  motion_[t].live = pose;
  moving_ = true;
}

void BaselineCore::sample_to_fluid(const sim::ParticleSet& p, float r) {
  fluid_grid_.build(p.position);
  fluid_grid_.query(p.position, xc, r, sf);
}

void BaselineCore::fluid_to_sample(const sim::ParticleSet& p, float r) {
  if (!sample_grid_valid_) sample_grid_.build(xc), sample_grid_valid_ = true;
  sample_grid_.query(xc, p.position, r, fs);
}

}  // namespace ff::control
