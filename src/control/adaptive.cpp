#include "control/adaptive.h"

#include "core/pair_loop.h"
#include "core/parallel.h"
#include "core/simd.h"
#include "sampling/weights.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace ff::control {
using core::parallel_for;

AdaptiveController::AdaptiveController(const ControlContext& ctx, const AdaptiveParams& params, float hc)
    : ctx_(ctx), params_(params), hc_(hc), d_(ctx.spacing()), poly6_(hc), spiky_(hc), ctrl_grid_(hc), fluid_grid_(hc) {}

Result<std::unique_ptr<AdaptiveController>> AdaptiveController::create(std::vector<ControlTarget> targets,
                                                                        const ControlContext& ctx,
                                                                        const AdaptiveParams& params) {
  FF_CHECK(params.validate());
  if (targets.empty()) return param_error("controller adaptive: the scene has no targets");
  if (targets.size() > 250) return param_error(fmt::format("controller adaptive: {} targets, at most 250", targets.size()));
  float hc = 0.0f;
  for (const auto& t : targets) {
    if (!t.set.consistent() || t.set.size() == 0 || !(t.set.support > 0.0f) || !(t.set.mass > 0.0f))
      return param_error(fmt::format("controller adaptive: target {} has no weighted control samples", t.set.target));
    if (hc > 0.0f && std::abs(t.set.support - hc) > 1e-4f * hc)
      return param_error(fmt::format("controller adaptive: targets have different control supports ({} m and {} m); "
                                     "sample them at one spacing", hc, t.set.support));
    hc = std::max(hc, t.set.support);
  }
  std::unique_ptr<AdaptiveController> c(new AdaptiveController(ctx, params, hc));
  for (std::size_t t = 0; t < targets.size(); ++t) {
    c->start_.push_back(targets[t].start);
    FF_CHECK(targets[t].motion.validate(fmt::format("targets[{}]", t)));
    c->motion_.push_back(targets[t].motion);
    c->moving_ = c->moving_ || targets[t].motion.moving();
    std::vector<Phase> phases;
    phases.push_back({-INFINITY, std::move(targets[t].set)});
    double last = -INFINITY;
    for (auto& [time, set] : targets[t].swaps) {
      if (!(time > last) || !std::isfinite(time))
        return param_error(fmt::format("targets[{}]: mesh swaps must come at increasing, finite times", t));
      if (!set.consistent() || set.size() == 0 || std::abs(set.support - hc) > 1e-4f * hc || !(set.mass > 0.0f))
        return param_error(fmt::format("targets[{}]: a swapped-in mesh has no control samples at the target's support", t));
      last = time;
      phases.push_back({time, std::move(set)});
    }
    c->phases_.push_back(std::move(phases));
  }
  c->current_.assign(targets.size(), 0);
  const float d = ctx.spacing(), mp = ctx.particle_mass;
  // ε_c = epsilon · S_0, S_0 = Σ_j |g_j|² over a full resting lattice neighbourhood, g_j = (m_p/ρ_ref) ∇W(k d, H_c)
  // with ρ_ref the lattice's kernel-sum density at H_c: what a filled interior sample sees (METHOD §a.3).
  const double rho_ref = sampling::lattice_density(d, hc, ctx.rest_density);
  const int reach = static_cast<int>(std::ceil(hc / d));
  double s0 = 0.0;
  for (int k = -reach; k <= reach; ++k)
    for (int j = -reach; j <= reach; ++j)
      for (int i = -reach; i <= reach; ++i) {
        if (!(i || j || k)) continue;
        s0 += ((mp / rho_ref) * c->spiky_.grad(Vec3f(float(i), float(j), float(k)) * d).cast<double>()).squaredNorm();
      }
  c->eps_c_ = static_cast<float>(params.epsilon * s0);
  c->flatten();
  // The gather field covers the domain at the control support (coarser on a huge domain).
  c->seed_field_.resize(targets.size());
  for (auto& f : c->seed_field_) f.reset(ctx.domain.min, ctx.domain.max, hc);
  return c;
}

// The samples of every target's current phase, flattened into the SoA arrays the loops use, with the
// per-sample boundary normals and g_ref (eq. 15–16). Run at the start and whenever a target swaps its mesh.
void AdaptiveController::flatten() {
  xc_.clear(), rho_c_.clear(), phi_.clear(), tc_.clear(), mass_c_.clear();
  for (std::size_t t = 0; t < phases_.size(); ++t) {
    const auto& s = phases_[t][current_[t]].set;
    mass_c_.push_back(s.mass);
    for (std::size_t i = 0; i < s.size(); ++i) {
      xc_.push_back(s.position[i]);
      rho_c_.push_back(s.density[i]);
      phi_.push_back(params_.weights ? s.phi[i] : 1.0f);
      tc_.push_back(static_cast<std::uint8_t>(t));
    }
  }
  // g_ref: the largest control-density gradient, which is found at the target surface (eq. 15 threshold).
  ctrl_grid_.build(xc_);
  core::NeighborList self;
  ctrl_grid_.query(xc_, xc_, hc_, self);
  const auto m = static_cast<std::int64_t>(xc_.size());
  grad_c_.resize(xc_.size());
  g_ref_ = static_cast<float>(core::deterministic_max(m, 0.0, [&](std::int64_t ii) {
    const auto i = static_cast<std::size_t>(ii);
    Vec3f g = Vec3f::Zero();
    for (Index j : self.of(i))
      if (tc_[j] == tc_[i]) g += mass_c_[tc_[i]] * spiky_.grad(xc_[i] - xc_[j]);
    grad_c_[i] = -g;  // n at the sample: minus the control-density gradient, pointing out of the target
    return static_cast<double>(g.norm());
  }));
  if (moving_) {
    rest_x_ = xc_;
    rest_grad_ = grad_c_;
    move_targets(time_);
  }
  fill_.assign(xc_.size(), 0.0f);
}

// Samples of keyframed targets follow their pose; densities keep their rest values (rigid motion keeps
// them exactly; a scale keyframe changes the volume to fill, which the fixed amount of fluid cannot follow).
void AdaptiveController::move_targets(double time) {
  std::vector<Pose> pose(motion_.size());
  for (std::size_t t = 0; t < motion_.size(); ++t) pose[t] = motion_[t].at(time);
  parallel_for(static_cast<std::int64_t>(xc_.size()), [&](std::int64_t ii) {
    const auto i = static_cast<std::size_t>(ii);
    const auto t = tc_[i];
    if (!motion_[t].moving()) return;
    xc_[i] = pose[t].apply(rest_x_[i]);
    grad_c_[i] = pose[t].rotation * rest_grad_[i];
  });
  ctrl_grid_.build(xc_);
}

void AdaptiveController::begin_step(const sim::StepView& view, sim::ParticleSet& p) {
  time_ = view.time;
  // A target whose mesh is swapped at this time (morph A → B) takes its next sample set: its fluid stays, and
  // the new samples pull it into the new shape.
  bool swapped = false;
  for (std::size_t t = 0; t < phases_.size(); ++t)
    while (current_[t] + 1 < phases_[t].size() && view.time >= phases_[t][current_[t] + 1].time) ++current_[t], swapped = true;
  if (swapped) flatten();
  else if (moving_) move_targets(view.time);
  const std::size_t n = p.size(), m = xc_.size();
  const Vec3f* x = p.position.data();
  const std::uint8_t* tf = p.target.data();
  // Pairs within H_c in both directions, on the positions at the start of the sub-step.
  fluid_grid_.build(p.position);
  fluid_grid_.query(p.position, xc_, hc_, cf_);
  ctrl_grid_.query(xc_, p.position, hc_, fc_);
  fill_.resize(m);
  hstar2_.resize(m);
  lambda_.assign(m, 0.0f);

  // ρ_p,i (eq. 8) at x, the fill ratio and the bond radius H_c*,i (eq. 19).
  const float mp = ctx_.particle_mass, hc2 = hc_ * hc_;
  parallel_for(static_cast<std::int64_t>(m), [&](std::int64_t ii) {
    const auto i = static_cast<std::size_t>(ii);
    float rho = 0.0f;
    if (active(tc_[i], time_)) {
      const Vec3f xi = xc_[i];
      const std::uint8_t t = tc_[i];
      for (Index j : cf_.of(i))
        if (tf[j] == t) rho += poly6_.w_r2((xi - x[j]).squaredNorm());
    }
    const float f = mp * rho / rho_c_[i];
    fill_[i] = f;
    float scale = 1.0f;
    if (params_.bond_breaking) {
      scale = params_.bond_radius == BondRadius::Paper ? 1.0f / (1.0f + f) : std::min(1.0f, 2.0f / (1.0f + f));
    }
    hstar2_[i] = hc2 * scale * scale;
  });

  // Bonds B(j), CSR: count, prefix, fill. A fluid particle is controlled iff it has a bond (METHOD §a.5).
  bond_off_.assign(n + 1, 0);
  parallel_for(static_cast<std::int64_t>(n), [&](std::int64_t jj) {
    const auto j = static_cast<std::size_t>(jj);
    Index c = 0;
    const std::uint8_t t = tf[j];
    if (active(t, time_))
      for (Index i : fc_.of(j))
        if (tc_[i] == t && (xc_[i] - x[j]).squaredNorm() <= hstar2_[i]) ++c;
    bond_off_[j + 1] = c;
  });
  for (std::size_t j = 0; j < n; ++j) bond_off_[j + 1] += bond_off_[j];
  bond_idx_.resize(bond_off_[n]);
  Index* bound = p.bound_control.data();
  parallel_for(static_cast<std::int64_t>(n), [&](std::int64_t jj) {
    const auto j = static_cast<std::size_t>(jj);
    Index o = bond_off_[j], nearest = kInvalidIndex;
    if (o == bond_off_[j + 1]) {
      bound[j] = kInvalidIndex;
      return;
    }
    const std::uint8_t t = tf[j];
    float best = INFINITY;
    for (Index i : fc_.of(j)) {
      if (tc_[i] != t) continue;
      const float r2 = (xc_[i] - x[j]).squaredNorm();
      if (r2 <= hstar2_[i]) {
        bond_idx_[o++] = i;
        if (r2 < best) best = r2, nearest = i;
      }
    }
    bound[j] = nearest;
  });
}

void AdaptiveController::add_accelerations(const sim::StepView& view, sim::ParticleSet& p) {
  const std::size_t n = p.size();
  Vec3f* a = p.acceleration.data();
  // Boundary correction (eq. 15–16): at a controlled particle, n = −Σ_i m_c ∇W(x_p − x_ci) points out of the
  // target; where it is strong (the surface band) the outward part of a_ext is removed, so gravity cannot
  // drag controlled fluid out through the lower surface.
  // n is taken at the particle's nearest bonded sample (precomputed: the control samples are static), not
  // summed over the ~270 samples around the particle: the two differ by less than a spacing in position, and
  // the sum cost as much as the whole control correction.
  if (params_.boundary_correction) {
    const float thr = params_.normal_threshold * g_ref_;
    const Index* bound = p.bound_control.data();
    parallel_for(static_cast<std::int64_t>(n), [&](std::int64_t jj) {
      const auto j = static_cast<std::size_t>(jj);
      const Index i = bound[j];
      if (i == kInvalidIndex) return;
      const Vec3f nrm = grad_c_[i];
      const float len = nrm.norm();
      if (!(len >= thr) || len == 0.0f) return;
      const Vec3f nh = nrm / len;
      const float out = nh.dot(a[j]);
      if (out > 0.0f) a[j] -= out * nh;
    });
  }
  // Speed limit of controlled fluid: v* = v + Δt a is brought back to max_speed through the acceleration.
  {
    const float vmax = params_.max_speed * d_, dt = view.dt;
    const Vec3f* v = p.velocity.data();
    parallel_for(static_cast<std::int64_t>(n), [&](std::int64_t jj) {
      const auto j = static_cast<std::size_t>(jj);
      if (bond_off_[j] == bond_off_[j + 1]) return;
      const Vec3f vs = v[j] + dt * a[j];
      const float s2 = vs.squaredNorm();
      if (s2 > vmax * vmax) a[j] += (vs * (vmax / std::sqrt(s2)) - vs) / dt;
    });
  }
  if (params_.gather) gather(p);
}

// Gather (ours, METHOD §a.10): an unbonded particle whose target still has under-filled samples is steered
// toward the nearest of them, at a limited speed, with gravity cancelled so it can rise into a target
// above it. It stops as soon as the particle is bonded (the control takes over) or the target is full.
void AdaptiveController::gather(sim::ParticleSet& p) {
  const std::size_t n = p.size(), m = xc_.size();
  // Which targets have unbonded fluid at all (once formed, none: the field is not worth computing).
  std::vector<char> wanted(seed_field_.size(), 0);
  for (std::size_t j = 0; j < n; ++j)
    if (p.target[j] < wanted.size() && bond_off_[j] == bond_off_[j + 1]) wanted[p.target[j]] = 1;
  for (std::size_t t = 0; t < seed_field_.size(); ++t) {
    seeds_.clear();
    if (wanted[t] && active(static_cast<std::uint8_t>(t), time_))
      for (std::size_t i = 0; i < m; ++i)
        if (tc_[i] == t && fill_[i] < params_.gather_fill) seeds_.push_back(static_cast<Index>(i));
    seed_field_[t].compute(xc_, seeds_);
  }
  const float speed = params_.gather_speed * d_, inv_tau = 1.0f / params_.gather_time;
  const Vec3f g = ctx_.gravity;
  const Vec3f* x = p.position.data();
  const Vec3f* v = p.velocity.data();
  Vec3f* a = p.acceleration.data();
  const std::uint8_t* tf = p.target.data();
  parallel_for(static_cast<std::int64_t>(n), [&](std::int64_t jj) {
    const auto j = static_cast<std::size_t>(jj);
    const std::uint8_t t = tf[j];
    if (t >= seed_field_.size() || bond_off_[j] != bond_off_[j + 1]) return;
    const Index s = seed_field_[t].nearest(x[j]);
    if (s == kInvalidIndex) return;
    const Vec3f to = xc_[s] - x[j];
    const float len = to.norm();
    if (len <= 0.0f) return;
    const Vec3f v_des = (speed / len) * to;
    a[j] += -g + inv_tau * (v_des - v[j]);
  });
}

// Eq. 17–18 as METHOD §a.5: a soft spring toward the bonded samples, stiffness f_i(r) = 1/(1 + (ρ_p/ρ_c) r/H_c),
// kernel-averaged so symmetric surroundings pull ~nothing. Once per sub-step.
void AdaptiveController::adaptive_spring(sim::ParticleSet& p, float dt) const {
  const std::size_t n = p.size();
  Vec3f* xs = p.predicted.data();
  const float gamma = params_.gamma * std::min(1.0f, dt / kReferenceDt), inv_hc = 1.0f / hc_;
  Vec3f* shift = p.shift.data();
  const bool kinematic = params_.kinematic;
  parallel_for(static_cast<std::int64_t>(n), [&](std::int64_t jj) {
    const auto j = static_cast<std::size_t>(jj);
    const Index b = bond_off_[j], e = bond_off_[j + 1];
    if (b == e) return;
    const Vec3f xj = xs[j];
    Vec3f num = Vec3f::Zero();
    float den = 0.0f;
    for (Index k = b; k < e; ++k) {
      const Index i = bond_idx_[k];
      const Vec3f r = xc_[i] - xj;
      const float r2 = r.squaredNorm();
      const float w = poly6_.w_r2(r2);
      if (w <= 0.0f) continue;
      const float f = 1.0f / (1.0f + fill_[i] * std::sqrt(r2) * inv_hc);
      num += (w * f) * r;
      den += w;
    }
    if (den > 0.0f) {
      const Vec3f dx = (gamma / den) * num;
      xs[j] = xj + dx;
      if (kinematic) shift[j] += dx;
    }
  });
}

// Eq. 6–10 (METHOD §a.3): per sample λ_i = −C_i/(Σ_j |g_ij|² + ε_c) with C_i = min(ρ_p,i/ρ_c,i − 1, 0) at x*,
// g_ij = −(m_p/ρ_c,i) ∇W(x_ci − x*_j); per fluid particle Δx_j = α Σ_{i∈B(j)} φ̃_i λ_i g_ij, at most clamp·d.
void AdaptiveController::control_correction(sim::ParticleSet& p, float dt) {
  using namespace core::simd;
  const std::size_t n = p.size(), m = xc_.size();
  if (n == 0) return;
  Vec3f* xs = p.predicted.data();
  const std::uint8_t* tf = p.target.data();
  const float mp = ctx_.particle_mass, eps = eps_c_;
  const bool multi = mass_c_.size() > 1;
  const __m128 h = broadcast(spiky_.h), h2 = broadcast(poly6_.h2), zero = _mm_setzero_ps();
  // Pairs of another target are masked off (only in a multi-target scene: one target needs no test).
  auto same_target = [&](const Index* j, std::uint8_t t) {
    return _mm_castsi128_ps(_mm_setr_epi32(tf[j[0]] == t ? -1 : 0, tf[j[1]] == t ? -1 : 0, tf[j[2]] == t ? -1 : 0,
                                           tf[j[3]] == t ? -1 : 0));
  };
  // λ per sample, four fluid neighbours at a time (core/pair_loop.h; padding lanes point at particle 0, masked).
  parallel_for(static_cast<std::int64_t>(m), [&](std::int64_t ii) {
    const auto i = static_cast<std::size_t>(ii);
    lambda_[i] = 0.0f;
    const std::uint8_t t = tc_[i];
    if (!active(t, time_)) return;
    const Vec3f xi = xc_[i];
    const __m128 px = broadcast(xi.x()), py = broadcast(xi.y()), pz = broadcast(xi.z());
    const auto range = cf_.of(i);
    auto r2_of = [&](const Index* j) {
      const V3 xj = core::simd::gather(xs, j[0], j[1], j[2], j[3]);
      const __m128 rx = _mm_sub_ps(px, xj.x), ry = _mm_sub_ps(py, xj.y), rz = _mm_sub_ps(pz, xj.z);
      return _mm_add_ps(_mm_add_ps(_mm_mul_ps(rx, rx), _mm_mul_ps(ry, ry)), _mm_mul_ps(rz, rz));
    };
    // Density first; the gradient sum (a square root per pair) only for the samples that are under-filled.
    __m128 sw = zero;
    core::for_neighbors4(range, 0, [&](const Index* j, __m128 lanes) {
      const __m128 r2 = r2_of(j);
      __m128 use = _mm_and_ps(lanes, _mm_cmplt_ps(r2, h2));
      if (multi) use = _mm_and_ps(use, same_target(j, t));
      const __m128 q2 = _mm_sub_ps(h2, r2);
      sw = _mm_add_ps(sw, select(use, _mm_mul_ps(_mm_mul_ps(q2, q2), q2)));
    });
    const float c = mp * poly6_.k * hsum(sw) / rho_c_[i] - 1.0f;
    if (c >= 0.0f) return;
    __m128 g2 = zero;
    core::for_neighbors4(range, 0, [&](const Index* j, __m128 lanes) {
      const __m128 r2 = r2_of(j);
      __m128 use = _mm_and_ps(lanes, _mm_cmplt_ps(r2, h2));
      if (multi) use = _mm_and_ps(use, same_target(j, t));
      const __m128 q = _mm_sub_ps(h, _mm_sqrt_ps(r2));
      const __m128 q2 = _mm_mul_ps(q, q);
      g2 = _mm_add_ps(g2, select(use, _mm_mul_ps(q2, q2)));  // |∇W|² = kgrad² (h − r)⁴
    });
    const float k = mp / rho_c_[i] * spiky_.kgrad;
    lambda_[i] = -c / (k * k * hsum(g2) + eps);
  });
  active_.clear();
  for (std::size_t i = 0; i < m; ++i)
    if (lambda_[i] > 0.0f) active_.push_back(static_cast<Index>(i));
  if (active_.empty()) return;  // every sample is full: no correction anywhere

  const float alpha = params_.alpha, max_dx = params_.clamp * d_ * std::min(1.0f, dt / kReferenceDt),
              max_dx2 = max_dx * max_dx;
  Vec3f* shift = p.shift.data();
  const bool kinematic = params_.kinematic;
  const float kg = -spiky_.kgrad;  // > 0: −∇W(r) = kg (h − |r|)² r̂ points along r = x_c − x_p (attraction)
  auto apply = [&](std::size_t j, Vec3f dx) {
    dx *= alpha;
    const float d2 = dx.squaredNorm();
    if (d2 > max_dx2) dx *= max_dx / std::sqrt(d2);
    xs[j] += dx;
    if (kinematic) shift[j] += dx;
  };
  // Δx_j = α Σ_{i∈B(j)} φ̃_i λ_i g_ij. Once a target has formed only a few (surface) samples are still under-filled:
  // then the sum is scattered from those samples (serially, in sample order: deterministic), instead of
  // every fluid particle walking its ~270 bonds to find them.
  if (active_.size() * 8 < m) {
    dx_.assign(n, Vec3f::Zero());
    touched_.assign(n, 0);
    const Vec3f* x = p.position.data();  // bonds were decided at the start of the sub-step
    for (Index i : active_) {
      const std::uint8_t t = tc_[i];
      const Vec3f xi = xc_[i];
      const float coef = phi_[i] * lambda_[i] * mp / rho_c_[i] * kg, hs2 = hstar2_[i];
      for (Index j : cf_.of(i)) {
        if (tf[j] != t || (xi - x[j]).squaredNorm() > hs2) continue;
        const Vec3f r = xi - xs[j];
        const float r2 = r.squaredNorm();
        if (r2 >= spiky_.h2 || r2 == 0.0f) continue;
        const float len = std::sqrt(r2), q = spiky_.h - len;
        dx_[j] += (coef * q * q / len) * r;
        touched_[j] = 1;
      }
    }
    parallel_for(static_cast<std::int64_t>(n), [&](std::int64_t jj) {
      const auto j = static_cast<std::size_t>(jj);
      if (touched_[j]) apply(j, dx_[j]);
    });
    return;
  }
  // Gather over the bonds, four at a time, with the per-sample factor φ̃ λ m_p/ρ_c kg precomputed (0 when full).
  coef_.resize(m);
  for (std::size_t i = 0; i < m; ++i) coef_[i] = lambda_[i] > 0.0f ? phi_[i] * lambda_[i] * mp / rho_c_[i] * kg : 0.0f;
  const __m128 sh = broadcast(spiky_.h), sh2 = broadcast(spiky_.h2);
  parallel_for(static_cast<std::int64_t>(n), [&](std::int64_t jj) {
    const auto j = static_cast<std::size_t>(jj);
    const Index b = bond_off_[j], e = bond_off_[j + 1];
    if (b == e) return;
    const Vec3f xj = xs[j];
    const __m128 px = broadcast(xj.x()), py = broadcast(xj.y()), pz = broadcast(xj.z());
    __m128 dx = zero, dy = zero, dz = zero;
    for (Index k = b; k < e; k += 4) {
      const Index left = e - k;
      const Index i0 = bond_idx_[k], i1 = left > 1 ? bond_idx_[k + 1] : i0, i2 = left > 2 ? bond_idx_[k + 2] : i0,
                  i3 = left > 3 ? bond_idx_[k + 3] : i0;
      const __m128 c4 = _mm_and_ps(core::simd::gather(coef_.data(), i0, i1, i2, i3), core::simd::first_lanes(left));
      if (_mm_movemask_ps(_mm_cmpgt_ps(c4, zero)) == 0) continue;
      const V3 xc = core::simd::gather(xc_.data(), i0, i1, i2, i3);
      const __m128 rx = _mm_sub_ps(xc.x, px), ry = _mm_sub_ps(xc.y, py), rz = _mm_sub_ps(xc.z, pz);
      const __m128 r2 = _mm_add_ps(_mm_add_ps(_mm_mul_ps(rx, rx), _mm_mul_ps(ry, ry)), _mm_mul_ps(rz, rz));
      const __m128 use = _mm_and_ps(_mm_cmplt_ps(r2, sh2), _mm_cmpgt_ps(r2, zero));
      const __m128 len = _mm_sqrt_ps(r2);
      const __m128 q = _mm_sub_ps(sh, len);
      const __m128 w = select(use, _mm_div_ps(_mm_mul_ps(c4, _mm_mul_ps(q, q)), len));
      dx = _mm_add_ps(dx, _mm_mul_ps(w, rx));
      dy = _mm_add_ps(dy, _mm_mul_ps(w, ry));
      dz = _mm_add_ps(dz, _mm_mul_ps(w, rz));
    }
    const Vec3f d(hsum(dx), hsum(dy), hsum(dz));
    if (d.squaredNorm() > 0.0f) apply(j, d);
  });
}

// The control acts in the nominal N_it iterations only: the solver's extra iterations (while the density error is
// high) are there to make the fluid incompressible, and more control sweeps would make the inflow depend on them.
void AdaptiveController::correct_positions(const sim::StepView& view, sim::ParticleSet& p) {
  if (view.iteration == 0 && params_.bond_breaking && params_.gamma > 0.0f) adaptive_spring(p, view.dt);
  if (view.iteration < std::max(1, view.iterations)) control_correction(p, view.dt);
}

}  // namespace ff::control
