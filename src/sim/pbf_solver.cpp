#include "sim/pbf_solver.h"

#include "core/parallel.h"
#include "core/timer.h"
#include "sim/pbf_constraints.h"

#include <Eigen/Geometry>  // cross product (vorticity)
#include <fmt/format.h>

#include <cmath>

namespace ff::sim {
using core::parallel_for;

PbfSolver::PbfSolver(const SolverParams& params, const Domain& domain)
    : params_(params),
      domain_(domain),
      poly6_(params.support()),
      spiky_(params.support()),
      grid_(params.support()) {
  const float d = params.spacing(), h = params.support(), r = params.particle_radius;
  mass_ = params.rest_density * d * d * d;
  // Calibrate ρ0 and S_0 on an interior point of the resting cubic lattice the emitter creates.
  const int reach = static_cast<int>(std::ceil(h / d));
  double sum_w = poly6_.w_zero();
  for (int k = -reach; k <= reach; ++k)
    for (int j = -reach; j <= reach; ++j)
      for (int i = -reach; i <= reach; ++i)
        if (i || j || k) sum_w += poly6_.w_r2(d * d * float(i * i + j * j + k * k));
  rho0_ = static_cast<float>(mass_ * sum_w);
  double s0 = 0.0;
  Vec3d grad_i = Vec3d::Zero();
  for (int k = -reach; k <= reach; ++k)
    for (int j = -reach; j <= reach; ++j)
      for (int i = -reach; i <= reach; ++i) {
        if (!(i || j || k)) continue;
        const Vec3f g = (mass_ / rho0_) * spiky_.grad(Vec3f(float(i), float(j), float(k)) * d);
        s0 += g.squaredNorm();
        grad_i += g.cast<double>();
      }
  s0 += grad_i.squaredNorm();
  s0_ = static_cast<float>(s0);
  epsilon_ = params.epsilon * s0_;
  w_dq_ = poly6_.w(params.scorr_dq * h);
  wall_lo_ = domain.min + Vec3f::Constant(r);
  wall_hi_ = domain.max - Vec3f::Constant(r);
}

std::size_t PbfSolver::scratch_bytes() const {
  return neighbors_.bytes() + grid_.bytes() + delta_.capacity() * sizeof(Vec3f) + omega_.capacity() * sizeof(Vec3f) +
         reorder_scratch_.v3.capacity() * sizeof(Vec3f) + reorder_scratch_.u32.capacity() * sizeof(Index) +
         reorder_scratch_.u8.capacity() + reorder_scratch_.f32.capacity() * sizeof(float);
}

void PbfSolver::search(ParticleSet& p) {
  grid_.build(p.position);
  // Re-sort by cell so that neighbours are close in memory; ids keep the identity of each particle.
  reorder(p, grid_.sorted(), reorder_scratch_);
  grid_.points_were_sorted();
  grid_.neighbors(p.position, neighbors_);
}

void PbfSolver::densities(std::span<const Vec3f> x, std::vector<float>& rho) const {
  const float w0 = poly6_.w_zero(), m = mass_;
  const Vec3f* xs = x.data();
  parallel_for(static_cast<std::int64_t>(x.size()), [&](std::int64_t ii) {
    const auto i = static_cast<std::size_t>(ii);
    const Vec3f xi = xs[i];
    float s = w0;
    for (Index j : neighbors_.of(i)) s += poly6_.w_r2((xi - xs[j]).squaredNorm());
    rho[i] = m * s;
  });
}

void PbfSolver::compute_densities(ParticleSet& p) {
  p.resize(p.size());
  search(p);
  densities(p.position, p.density);
}

// a_ext = g + XSPH viscosity in the seed's acceleration form (eq. 12, sign fixed as METHOD.md §a.4):
//   a_vis,i = (η/Δt) Σ_j (m/ρ_j)(v_j − v_i) W(x_i − x_j, H_p)
void PbfSolver::external_accelerations(ParticleSet& p, float dt) const {
  const Vec3f g = params_.gravity;
  const float c = params_.viscosity / dt, m = mass_;
  const Vec3f* x = p.position.data();
  const Vec3f* v = p.velocity.data();
  const float* rho = p.density.data();
  Vec3f* a = p.acceleration.data();
  if (c == 0.0f) {
    parallel_for(static_cast<std::int64_t>(p.size()), [&](std::int64_t i) { a[i] = g; });
    return;
  }
  parallel_for(static_cast<std::int64_t>(p.size()), [&](std::int64_t ii) {
    const auto i = static_cast<std::size_t>(ii);
    const Vec3f xi = x[i], vi = v[i];
    Vec3f s = Vec3f::Zero();
    for (Index j : neighbors_.of(i)) s += (m / rho[j] * poly6_.w_r2((xi - x[j]).squaredNorm())) * (v[j] - vi);
    a[i] = g + c * s;
  });
}

void PbfSolver::clamp_to_walls(std::vector<Vec3f>& x) const {
  const Vec3f lo = wall_lo_, hi = wall_hi_;
  parallel_for(static_cast<std::int64_t>(x.size()), [&](std::int64_t i) { x[i] = x[i].cwiseMax(lo).cwiseMin(hi); });
}

void PbfSolver::solve_iteration(ParticleSet& p) {
  const std::size_t n = p.size();
  const Vec3f* xs = p.predicted.data();
  float* lambda = p.lambda.data();
  float* rho = p.density.data();
  const float m = mass_, w0 = poly6_.w_zero(), m_rho0 = mass_ / rho0_, rho0 = rho0_, eps = epsilon_;
  const float h = spiky_.h, h2 = spiky_.h2;

  // λ_i from the density at x* (Poly6) and the constraint gradients (Spiky).
  parallel_for(static_cast<std::int64_t>(n), [&](std::int64_t ii) {
    const auto i = static_cast<std::size_t>(ii);
    const Vec3f xi = xs[i];
    float sum_w = w0, grad_sq = 0.0f;
    Vec3f grad_i = Vec3f::Zero();
    for (Index j : neighbors_.of(i)) {
      const Vec3f r = xi - xs[j];
      const float r2 = r.squaredNorm();
      if (r2 >= h2) continue;
      sum_w += poly6_.w_r2(r2);
      const float len = std::sqrt(r2);
      if (len <= 0.0f) continue;
      const Vec3f g = m_rho0 * spiky_.grad(r, len);
      grad_sq += g.squaredNorm();
      grad_i += g;
    }
    rho[i] = m * sum_w;
    lambda[i] = pbf_lambda(density_constraint(rho[i], rho0), grad_sq + grad_i.squaredNorm(), eps);
  });

  // Δx_i = (m/ρ0) Σ_j (λ_i + λ_j + s_corr) ∇W(x_i − x_j)
  const float k = params_.scorr_k, inv_wdq = 1.0f / w_dq_, s0 = s0_;
  const int sn = params_.scorr_n;
  Vec3f* delta = delta_.data();
  parallel_for(static_cast<std::int64_t>(n), [&](std::int64_t ii) {
    const auto i = static_cast<std::size_t>(ii);
    const Vec3f xi = xs[i];
    const float li = lambda[i];
    Vec3f dx = Vec3f::Zero();
    for (Index j : neighbors_.of(i)) {
      const Vec3f r = xi - xs[j];
      const float r2 = r.squaredNorm();
      if (r2 >= h2) continue;
      const float len = std::sqrt(r2);
      if (len <= 0.0f) continue;
      const float scorr = k > 0.0f ? pbf_scorr(poly6_.w_r2(r2) * inv_wdq, k, sn, s0) : 0.0f;
      const float q = h - len;
      // Spiky gradient inlined: ∇W = kgrad (h − |r|)² r/|r|.
      dx += ((li + lambda[j] + scorr) * spiky_.kgrad * q * q / len) * r;
    }
    delta[i] = m_rho0 * dx;
  });
  Vec3f* xw = p.predicted.data();
  const Vec3f lo = wall_lo_, hi = wall_hi_;
  parallel_for(static_cast<std::int64_t>(n), [&](std::int64_t i) { xw[i] = (xw[i] + delta[i]).cwiseMax(lo).cwiseMin(hi); });
}

// Vorticity confinement (Fedkiw 2001 as used by PBF): ω_i = Σ (m/ρ_j)(v_j − v_i) × ∇W_ij,
// η_i = Σ (m/ρ_j) |ω_j| ∇W_ij, N = η/|η|, v_i += Δt ε_v (N × ω_i).
void PbfSolver::vorticity_confinement(ParticleSet& p, float dt) {
  const std::size_t n = p.size();
  omega_.resize(n);
  const Vec3f* x = p.position.data();
  const Vec3f* v = p.velocity.data();
  const float* rho = p.density.data();
  const float m = mass_;
  parallel_for(static_cast<std::int64_t>(n), [&](std::int64_t ii) {
    const auto i = static_cast<std::size_t>(ii);
    Vec3f w = Vec3f::Zero();
    for (Index j : neighbors_.of(i)) w += (m / rho[j]) * (v[j] - v[i]).cross(spiky_.grad(x[i] - x[j]));
    omega_[i] = w;
  });
  const float c = dt * params_.vorticity;
  Vec3f* vw = p.velocity.data();
  parallel_for(static_cast<std::int64_t>(n), [&](std::int64_t ii) {
    const auto i = static_cast<std::size_t>(ii);
    Vec3f eta = Vec3f::Zero();
    for (Index j : neighbors_.of(i)) eta += (m / rho[j]) * omega_[j].norm() * spiky_.grad(x[i] - x[j]);
    const float len = eta.norm();
    if (len > 1e-12f) vw[i] += c * (eta / len).cross(omega_[i]);
  });
}

void PbfSolver::substep(ParticleSet& p, double time, float dt, Controller& controller, StageTimes& times) {
  const std::size_t n = p.size();
  StepView view{dt, time, -1, params_.particle_radius, &neighbors_};
  {
    core::ScopedTimer t(times.neighbors);
    p.resize(n);
    delta_.resize(n);
    search(p);
  }
  {
    core::ScopedTimer t(times.forces);
    densities(p.position, p.density);
    external_accelerations(p, dt);
  }
  {
    core::ScopedTimer t(times.control);
    controller.begin_step(view, p);
    controller.add_accelerations(view, p);
  }
  {
    core::ScopedTimer t(times.update);
    Vec3f* v = p.velocity.data();
    Vec3f* xs = p.predicted.data();
    const Vec3f* x = p.position.data();
    const Vec3f* a = p.acceleration.data();
    const Vec3f lo = wall_lo_, hi = wall_hi_;
    parallel_for(static_cast<std::int64_t>(n), [&](std::int64_t i) {
      const Vec3f vs = v[i] + dt * a[i];
      xs[i] = (x[i] + dt * vs).cwiseMax(lo).cwiseMin(hi);
    });
  }
  // At least `iterations` Jacobi sweeps; more (up to max_iterations) while the mean compression, measured
  // by each sweep's density pass, is above max_density_error (SPlisHSPlasH's PBF stops the same way).
  // A deep column needs this: with 4 sweeps a 27-layer column settles ~1.7 % compressed.
  const double target = params_.max_density_error, rho0 = rho0_;
  const auto ni = static_cast<std::int64_t>(n);
  for (int it = 0; it < params_.max_iterations; ++it) {
    {
      core::ScopedTimer t(times.control);
      view.iteration = it;
      controller.correct_positions(view, p);
    }
    core::ScopedTimer t(times.solve);
    solve_iteration(p);
    ++times.iterations;
    if (it + 1 >= params_.iterations) {
      const double err = ni ? core::deterministic_sum(ni, [&](std::int64_t i) {
        return static_cast<double>(density_constraint(p.density[static_cast<std::size_t>(i)], static_cast<float>(rho0)));
      }) / double(ni) : 0.0;
      if (err <= target) break;
    }
  }
  {
    core::ScopedTimer t(times.update);
    const float inv_dt = 1.0f / dt;
    Vec3f* v = p.velocity.data();
    const Vec3f* xs = p.predicted.data();
    const Vec3f* x = p.position.data();
    parallel_for(static_cast<std::int64_t>(n), [&](std::int64_t i) { v[i] = (xs[i] - x[i]) * inv_dt; });
    if (params_.vorticity > 0.0f) vorticity_confinement(p, dt);
    p.position.swap(p.predicted);
  }
  {
    core::ScopedTimer t(times.control);
    view.iteration = -1;
    controller.end_step(view, p);
  }
}

Result<FrameStats> PbfSolver::advance(ParticleSet& p, double time, double frame_dt, Controller& controller) {
  FrameStats stats;
  const auto n = static_cast<std::int64_t>(p.size());
  // Sub-step from the CFL condition on the fastest particle, allowing for gravity's speed-up over the frame.
  const double vmax = std::sqrt(core::deterministic_max(n, 0.0, [&](std::int64_t i) {
    return static_cast<double>(p.velocity[static_cast<std::size_t>(i)].squaredNorm());
  }));
  const double v_est = vmax + params_.gravity.norm() * frame_dt;
  const double dt_cfl = cfl_dt(static_cast<float>(v_est), params_.spacing(), params_.cfl, params_.max_dt);
  int steps = static_cast<int>(std::ceil(frame_dt / dt_cfl - 1e-9));
  steps = std::max(steps, 1);
  if (steps > params_.max_substeps) {
    steps = params_.max_substeps;
    stats.substeps_capped = true;
  }
  const float dt = static_cast<float>(frame_dt / steps);
  // A blow-up stops the run naming a bad particle. The state is checked before stepping and after every
  // sub-step, so the named particle is one where the NaN/Inf appeared, before neighbours spread it further
  // (lowest id among those, so the message is deterministic).
  auto first_bad = [&]() {  // only on the error path: a plain serial scan
    Index bad = kInvalidIndex;
    for (std::size_t i = 0; i < p.size(); ++i)
      if (!p.position[i].allFinite() || !p.velocity[i].allFinite()) bad = std::min(bad, p.id[i]);
    return bad;
  };
  auto any_bad = [&]() {
    return core::deterministic_max(n, 0.0, [&](std::int64_t i) {
      const auto k = static_cast<std::size_t>(i);
      return p.position[k].allFinite() && p.velocity[k].allFinite() ? 0.0 : 1.0;
    }) > 0.0;
  };
  auto blown = [&](Index id, int step) {
    return numerical_error(fmt::format("simulation blew up in sub-step {}: particle {} has a non-finite position or velocity",
                                       step, id));
  };
  if (any_bad()) return blown(first_bad(), 0);
  for (int s = 0; s < steps; ++s) {
    substep(p, time + s * double(dt), dt, controller, stats.times);
    if (any_bad()) return blown(first_bad(), s + 1);
  }
  stats.substeps = steps;
  stats.dt = dt;

  // Density error at the end of the frame, from the densities of the last iteration.
  const float rho0 = rho0_;
  stats.density_error_mean = n ? core::deterministic_sum(n, [&](std::int64_t i) {
    return static_cast<double>(density_constraint(p.density[static_cast<std::size_t>(i)], rho0));
  }) / double(n) : 0.0;
  stats.density_error_max = core::deterministic_max(n, 0.0, [&](std::int64_t i) {
    return static_cast<double>(density_constraint(p.density[static_cast<std::size_t>(i)], rho0));
  });
  stats.max_speed = std::sqrt(core::deterministic_max(n, 0.0, [&](std::int64_t i) {
    return static_cast<double>(p.velocity[static_cast<std::size_t>(i)].squaredNorm());
  }));
  return stats;
}

}  // namespace ff::sim
