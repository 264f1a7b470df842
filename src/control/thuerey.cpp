#include "control/thuerey.h"

#include "core/kernels.h"
#include "core/parallel.h"

#include <cmath>
#include <numbers>

namespace ff::control {
namespace {
// El'Beem's attraction fall-off: full strength in the inner half, then linear to 0 at R_a.
inline float w_attract(float r, float ra) { return r < 0.5f * ra ? 1.0f : r < ra ? 2.0f * (1.0f - r / ra) : 0.0f; }
}  // namespace

Result<std::unique_ptr<ThuereyController>> ThuereyController::create(std::vector<ControlTarget> targets,
                                                                     const ControlContext& ctx, const ThuereyParams& params) {
  FF_CHECK(params.validate());
  std::unique_ptr<ThuereyController> c(new ThuereyController(params));
  FF_CHECK(c->harness_.init(std::move(targets), ctx, "thuerey"));
  c->ra_ = params.radius * c->harness_.hc;
  const double rf = params.fill_radius * c->ra_, d = c->harness_.d;
  c->n_full_ = static_cast<float>(4.0 / 3.0 * std::numbers::pi * rf * rf * rf / (d * d * d));
  return c;
}

void ThuereyController::begin_step(const sim::StepView& view, sim::ParticleSet& p) {
  harness_.update(view.time, view.dt);
  harness_.sample_to_fluid(p, ra_);
  harness_.fluid_to_sample(p, ra_);
  const std::size_t m = harness_.samples.position.size();
  q_.resize(m);
  const Vec3f* x = p.position.data();
  core::parallel_for(static_cast<std::int64_t>(m), [&](std::int64_t ii) {
    const auto i = static_cast<std::size_t>(ii);
    float fill = 0.0f;
    for (Index j : harness_.near_fluid.of(i))
      if (harness_.pairs(p.target[j], static_cast<Index>(i))) fill += w_attract((x[j] - harness_.samples.position[i]).norm(), ra_);
    q_[i] = std::clamp(1.0f - fill / n_full_, 0.0f, 1.0f);
  });
}

void ThuereyController::add_accelerations(const sim::StepView& view, sim::ParticleSet& p) {
  const std::size_t n = p.size();
  const Vec3f* x = p.position.data();
  const Vec3f* v = p.velocity.data();
  const float* rho = p.density.data();
  const float alpha = params_.attraction;
  const float beta_dt = 1.0f - std::pow(1.0f - params_.velocity, view.dt / 0.01f);
  const float inv_dt = 1.0f / view.dt;
  // The low-pass velocity ṽ_p is the Poly6 (Shepard) average over the solver's neighbours within H_p.
  const core::Poly6 smooth(harness_.ctx.support());
  core::parallel_for(static_cast<std::int64_t>(n), [&](std::int64_t jj) {
    const auto j = static_cast<std::size_t>(jj);
    p.bound_control[j] = kInvalidIndex;
    const std::uint8_t t = p.target[j];
    if (!harness_.live_target(t)) return;
    Vec3f att = Vec3f::Zero(), u = Vec3f::Zero();
    float omega = 0.0f, wv = 0.0f, best = INFINITY;
    for (Index i : harness_.near_samples.of(j)) {
      if (!harness_.pairs(t, i)) continue;
      const Vec3f r = harness_.samples.position[i] - x[j];
      const float len = r.norm();
      if (len >= ra_) continue;
      if (len < best) best = len, p.bound_control[j] = i;
      const float w = 1.0f - len / ra_;  // El'Beem divides by the attraction radius here too
      u += w * harness_.samples.velocity[i], wv += w;
      if (q_[i] > 0.0f && len > 1e-9f) att += (q_[i] / len) * r, omega += q_[i] * w_attract(len, ra_);
    }
    if (p.bound_control[j] == kInvalidIndex) return;
    const float scale = omega <= 1.0f ? omega : 1.0f / omega;
    Vec3f a = alpha * scale * att;
    if (wv > 0.0f && beta_dt > 0.0f) {
      float ws = smooth.w_zero() / rho[j];
      Vec3f vs = ws * v[j];
      if (view.fluid_neighbors)
        for (Index k : view.fluid_neighbors->of(j)) {
          const float w = smooth.w_r2((x[j] - x[k]).squaredNorm()) / rho[k];
          vs += w * v[k], ws += w;
        }
      const Vec3f low = vs / ws;
      a += beta_dt * std::min(1.0f, wv) * (u / wv - low) * inv_dt;
    }
    p.acceleration[j] += a;
  });
}

}  // namespace ff::control
