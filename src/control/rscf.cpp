#include "control/rscf.h"

#include "core/kernels.h"
#include "core/parallel.h"

namespace ff::control {
namespace {
constexpr float kRefDt = 1.0f / 60.0f;  // Δt_ref of METHOD §b.2
}

Result<std::unique_ptr<RscfController>> RscfController::create(std::vector<ControlTarget> targets,
                                                               const ControlContext& ctx, const RscfParams& params) {
  FF_CHECK(params.validate());
  std::unique_ptr<RscfController> c(new RscfController(params));
  FF_CHECK(c->harness_.init(std::move(targets), ctx, "rscf"));
  return c;
}

void RscfController::begin_step(const sim::StepView& view, sim::ParticleSet& p) {
  harness_.update(view.time, view.dt);
  harness_.fluid_to_sample(p, harness_.hc);
}

void RscfController::add_accelerations(const sim::StepView&, sim::ParticleSet& p) {
  const core::Poly6 poly6(harness_.hc);
  const core::Spiky spiky(harness_.hc);
  const float kx = params_.position / (kRefDt * kRefDt), kv = params_.velocity / kRefDt;
  const Vec3f* x = p.position.data();
  core::parallel_for(static_cast<std::int64_t>(p.size()), [&](std::int64_t jj) {
    const auto j = static_cast<std::size_t>(jj);
    p.bound_control[j] = kInvalidIndex;
    const std::uint8_t t = p.target[j];
    if (!harness_.live_target(t)) return;
    Vec3f xbar = Vec3f::Zero(), ubar = Vec3f::Zero();
    float wsum = 0.0f, best = INFINITY;
    for (Index i : harness_.near_samples.of(j)) {
      if (!harness_.pairs(t, i)) continue;
      const float r2 = (x[j] - harness_.samples.position[i]).squaredNorm();
      if (r2 < best) best = r2, p.bound_control[j] = i;
      const float w = poly6.w_r2(r2);
      xbar += w * harness_.samples.position[i], ubar += w * harness_.samples.velocity[i], wsum += w;
    }
    if (!(wsum > 0.0f)) return;
    xbar /= wsum, ubar /= wsum;
    // First-order feature: the SPH velocity gradient of the rig, G δ = Σ_i V_i (u_i − ū) (∇W_i · δ).
    if (params_.gradient > 0.0f) {
      const Vec3f delta = x[j] - xbar;
      Vec3f gu = Vec3f::Zero();
      for (Index i : harness_.near_samples.of(j)) {
        if (!harness_.pairs(t, i)) continue;
        const float vol = harness_.samples.mass[harness_.samples.target[i]] / harness_.samples.rho_c[i];
        gu += vol * spiky.grad(x[j] - harness_.samples.position[i]).dot(delta) * (harness_.samples.velocity[i] - ubar);
      }
      ubar += params_.gradient * gu;
    }
    p.acceleration[j] += kx * (xbar - x[j]) + kv * (ubar - p.velocity[j]);
  });
}

}  // namespace ff::control
