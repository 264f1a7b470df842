#include "control/density_spring.h"

#include "control/adaptive_params.h"

#include "core/kernels.h"
#include "core/parallel.h"
#include "sampling/weights.h"

#include <cmath>

namespace ff::control {

Result<std::unique_ptr<DensitySpringController>> DensitySpringController::create(std::vector<ControlTarget> targets,
                                                                                 const ControlContext& ctx,
                                                                                 DensitySpringConfig cfg) {
  std::unique_ptr<DensitySpringController> c(new DensitySpringController(std::move(cfg)));
  for (const auto& t : targets) c->moving_ = c->moving_ || t.motion.moving();
  FF_CHECK(c->harness_.init(std::move(targets), ctx, c->cfg_.name));
  const float hc = c->harness_.hc, d = c->harness_.d;
  // ρ_0: the kernel-sum density a full fluid neighbourhood gives at H_c (the calibration of m_c, METHOD §a.3).
  const double rho_ref = sampling::lattice_density(d, hc, ctx.rest_density);
  c->rho0_ = static_cast<float>(rho_ref);
  c->eps_c_ = static_cast<float>(c->cfg_.epsilon * full_gradient_sum(d, hc, ctx.particle_mass, rho_ref));
  c->sample_weights();
  return c;
}

// w_i from the colour field of the samples with a fixed sample volume V_c = d³ (METHOD §b.4): ≈ 1 inside, lower
// at the surface and where samples are sparse, so those control particles pull harder.
void DensitySpringController::sample_weights() {
  const std::size_t m = harness_.samples.position.size();
  w_.assign(m, 1.0f);
  if (!(cfg_.kappa > 0.0f)) return;
  const core::Poly6 w(harness_.hc);
  core::NeighborGrid grid(harness_.hc);
  grid.build(harness_.samples.position);
  core::NeighborList self;
  grid.neighbors(harness_.samples.position, self);
  const float vc = harness_.d * harness_.d * harness_.d;
  std::vector<float> cf(m);
  core::parallel_for(static_cast<std::int64_t>(m), [&](std::int64_t ii) {
    const auto i = static_cast<std::size_t>(ii);
    float s = w.w_zero();
    for (Index j : self.of(i))
      if (harness_.samples.target[j] == harness_.samples.target[i]) s += w.w_r2((harness_.samples.position[i] - harness_.samples.position[j]).squaredNorm());
    cf[i] = vc * s;
  });
  float top = 0.0f;
  for (float v : cf) top = std::max(top, v);
  for (std::size_t i = 0; i < m; ++i) w_[i] = 1.0f + cfg_.kappa * (1.0f - cf[i] / top);
}

void DensitySpringController::begin_step(const sim::StepView& view, sim::ParticleSet& p) {
  if (harness_.update(view.time, view.dt)) {
    // A mesh swap renumbers the control particles: springs start over, weights are recomputed.
    std::fill(ref_.begin(), ref_.end(), kInvalidIndex);
    std::fill(life_.begin(), life_.end(), 0);
    sample_weights();
  }
  harness_.sample_to_fluid(p, harness_.hc);
  harness_.fluid_to_sample(p, harness_.hc);
  const std::size_t n = p.size();
  Index max_id = 0;
  for (std::size_t j = 0; j < n; ++j) max_id = std::max(max_id, p.id[j]);
  if (ref_.size() <= max_id) ref_.resize(max_id + 1, kInvalidIndex), life_.resize(max_id + 1, 0);
  // The spring's reference: the nearest control particle while within D/2, kept T sub-steps after leaving.
  const float reach2 = 0.25f * cfg_.bond_reach * cfg_.bond_reach * harness_.hc * harness_.hc;
  const Vec3f* x = p.position.data();
  core::parallel_for(static_cast<std::int64_t>(n), [&](std::int64_t jj) {
    const auto j = static_cast<std::size_t>(jj);
    const Index id = p.id[j];
    const std::uint8_t t = p.target[j];
    Index best = kInvalidIndex;
    float best2 = INFINITY;
    for (Index i : harness_.near_samples.of(j)) {
      if (!harness_.pairs(t, i)) continue;
      const float r2 = (harness_.samples.position[i] - x[j]).squaredNorm();
      if (r2 < best2) best2 = r2, best = i;
    }
    if (best != kInvalidIndex && best2 <= reach2) ref_[id] = best, life_[id] = cfg_.lifetime;
    else if (life_[id] > 0 && !harness_.live_target(t)) life_[id] = 0;
    else if (life_[id] > 0) --life_[id];
    if (life_[id] <= 0) ref_[id] = kInvalidIndex;
    p.bound_control[j] = best != kInvalidIndex ? best : ref_[id];
  });
}

void DensitySpringController::correct_positions(const sim::StepView& view, sim::ParticleSet& p) {
  if (view.iteration != 0) return;  // once per sub-step, before the PBF iterations
  const std::size_t n = p.size(), m = harness_.samples.position.size();
  const Vec3f* xs = p.predicted.data();
  const float mp = harness_.ctx.particle_mass;
  const core::Poly6 poly6(harness_.hc);
  const core::Spiky spiky(harness_.hc);
  // 1. λ_i at x*.
  lambda_.resize(m);
  core::parallel_for(static_cast<std::int64_t>(m), [&](std::int64_t ii) {
    const auto i = static_cast<std::size_t>(ii);
    lambda_[i] = 0.0f;
    if (!harness_.live_target(harness_.samples.target[i])) return;
    const float rho0 = cfg_.per_sample_density ? harness_.samples.rho_c[i] : rho0_;
    float rho = 0.0f, sum_g2 = 0.0f;
    for (Index j : harness_.near_fluid.of(i)) {
      if (p.target[j] != harness_.samples.target[i]) continue;
      const Vec3f r = harness_.samples.position[i] - xs[j];
      rho += mp * poly6.w_r2(r.squaredNorm());
      sum_g2 += ((mp / rho0) * spiky.grad(r)).squaredNorm();
    }
    lambda_[i] = -(rho / rho0 - 1.0f) / (sum_g2 + eps_c_);
  });
  // The published form runs at a fixed Δt = Δt_ref = 1/120 s. Our harness sub-steps by the CFL rule, and a
  // position correction of fixed size becomes a faster velocity as Δt shrinks, which shrinks Δt again: so the
  // density and spring corrections are scaled by Δt/Δt_ref (as `adaptive`'s clamp and spring are), which keeps the
  // velocity they impart what it is at Δt_ref.
  const float scale = std::min(1.0f, view.dt / kReferenceDt);
  const float alpha = cfg_.alpha * scale, beta = cfg_.spring * harness_.d * scale, a = cfg_.steepness / harness_.hc;
  const float b = cfg_.spring_start * harness_.hc;
  const float gamma = (moving_ ? cfg_.velocity_moving : cfg_.velocity) * view.dt;
  core::parallel_for(static_cast<std::int64_t>(n), [&](std::int64_t jj) {
    const auto j = static_cast<std::size_t>(jj);
    const std::uint8_t t = p.target[j];
    if (!harness_.live_target(t)) return;
    Vec3f dx = Vec3f::Zero(), u = Vec3f::Zero();
    float wu = 0.0f;
    for (Index i : harness_.near_samples.of(j)) {
      if (!harness_.pairs(t, i)) continue;
      const float rho0 = cfg_.per_sample_density ? harness_.samples.rho_c[i] : rho0_;
      const Vec3f r = harness_.samples.position[i] - xs[j];
      dx -= (alpha * w_[i] * lambda_[i] * mp / rho0) * spiky.grad(r);
      const float w = poly6.w_r2(r.squaredNorm());
      u += w * harness_.samples.velocity[i], wu += w;
    }
    // 3. Velocity constraint, on the particle's predicted velocity.
    if (wu > 0.0f && gamma > 0.0f) dx += gamma * (u / wu - p.velocity[j]);
    // 2. Spring toward the reference, only once the particle has drifted away from it.
    const Index r = ref_[p.id[j]];
    if (r != kInvalidIndex && beta > 0.0f) {
      const Vec3f to = harness_.samples.position[r] - xs[j];
      const float len = to.norm();
      if (len > 1e-9f) dx += (beta / (1.0f + std::exp(a * (b - len))) / len) * to;
    }
    p.predicted[j] += dx;
  });
}

}  // namespace ff::control
