#include "control/lcat.h"

#include "core/kernels.h"
#include "core/parallel.h"

#include <cmath>

namespace ff::control {
namespace {
constexpr float kRefDt = 1.0f / 60.0f;  // Δt_ref of METHOD §b.3
}

Result<std::unique_ptr<LcatController>> LcatController::create(std::vector<ControlTarget> targets,
                                                               const ControlContext& ctx, const LcatParams& params) {
  FF_CHECK(params.validate());
  std::unique_ptr<LcatController> c(new LcatController(params));
  FF_CHECK(c->harness_.init(std::move(targets), ctx, "lcat"));
  return c;
}

void LcatController::begin_step(const sim::StepView& view, sim::ParticleSet& p) {
  harness_.update(view.time, view.dt);
  harness_.sample_to_fluid(p, harness_.hc);
  harness_.fluid_to_sample(p, harness_.hc);
  const std::size_t m = harness_.samples.position.size();
  delta_.resize(m);
  wants_.resize(m);
  const core::Poly6 poly6(harness_.hc);
  const float mp = harness_.ctx.particle_mass, near2 = 0.25f * harness_.d * harness_.d;
  const Vec3f* x = p.position.data();
  core::parallel_for(static_cast<std::int64_t>(m), [&](std::int64_t ii) {
    const auto i = static_cast<std::size_t>(ii);
    float rho = 0.0f, nearest2 = INFINITY;
    for (Index j : harness_.near_fluid.of(i)) {
      if (p.target[j] != harness_.samples.target[i]) continue;
      const float r2 = (x[j] - harness_.samples.position[i]).squaredNorm();
      rho += mp * poly6.w_r2(r2), nearest2 = std::min(nearest2, r2);
    }
    const float fill = rho / harness_.samples.rho_c[i];
    const bool live = harness_.live_target(harness_.samples.target[i]);
    delta_[i] = live ? std::max(0.0f, 1.0f - fill) : 0.0f;
    wants_[i] = live && fill < params_.spawn_fill && nearest2 > near2 ? 1 : 0;
  });
}

void LcatController::add_accelerations(const sim::StepView&, sim::ParticleSet& p) {
  const core::Poly6 poly6(harness_.hc);
  const float w0 = poly6.w_zero(), kv = params_.velocity / kRefDt;
  const Vec3f* x = p.position.data();
  if (temporary_.size() < p.size()) temporary_.resize(p.size(), 0);
  core::parallel_for(static_cast<std::int64_t>(p.size()), [&](std::int64_t jj) {
    const auto j = static_cast<std::size_t>(jj);
    p.bound_control[j] = kInvalidIndex;
    const std::uint8_t t = p.target[j];
    if (!harness_.live_target(t)) return;
    Vec3f pull = Vec3f::Zero(), u = Vec3f::Zero();
    float wsum = 0.0f, best = INFINITY;
    for (Index i : harness_.near_samples.of(j)) {
      if (!harness_.pairs(t, i)) continue;
      const Vec3f r = harness_.samples.position[i] - x[j];
      const float r2 = r.squaredNorm(), w = poly6.w_r2(r2);
      if (r2 < best) best = r2, p.bound_control[j] = i;
      if (r2 > 1e-18f) pull += (delta_[i] * w / std::sqrt(r2)) * r;
      u += w * harness_.samples.velocity[i], wsum += w;
    }
    if (!(wsum > 0.0f)) return;
    p.acceleration[j] += params_.density * pull / std::max(1.0f, wsum / w0) + kv * (u / wsum - p.velocity[j]);
  });
  // Temporaries are controlled for as long as they live (the whole run), wherever they are.
  for (std::size_t j = 0; j < p.size(); ++j)
    if (p.bound_control[j] == kInvalidIndex && p.id[j] < temporary_.size() && temporary_[p.id[j]])
      p.bound_control[j] = 0;
}

void LcatController::emit(const sim::StepView&, sim::ParticleSet& p) {
  std::size_t templ = 0;
  for (std::size_t i = 0; i < harness_.samples.position.size(); ++i) templ += harness_.live_target(harness_.samples.target[i]) ? 1 : 0;
  const auto cap = static_cast<std::size_t>(std::floor(params_.temporaries * double(templ)));
  // In sample order, so the spawned particles (and their ids) are the same for any thread count.
  for (std::size_t i = 0; i < wants_.size() && spawned_ < cap; ++i) {
    if (!wants_[i]) continue;
    p.push_back(harness_.samples.position[i], harness_.samples.velocity[i], harness_.samples.target[i]);
    const Index id = p.id.back();
    if (temporary_.size() <= id) temporary_.resize(id + 1, 0);
    temporary_[id] = 1;
    ++spawned_;
  }
  std::fill(wants_.begin(), wants_.end(), std::uint8_t{0});
}

}  // namespace ff::control
