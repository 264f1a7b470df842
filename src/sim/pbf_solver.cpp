#include "sim/pbf_solver.h"

#include "core/parallel.h"
#include "core/timer.h"
#include "core/pair_loop.h"
#include "sim/drag.h"
#include "sim/pbf_constraints.h"
#include "sim/pbf_kernels.h"

#include <Eigen/Geometry>  // cross product (vorticity)
#include <fmt/format.h>

#include <cmath>
#include <type_traits>

namespace ff::sim {
using core::parallel_for;
using core::for_neighbors4;

PbfSolver::PbfSolver(const SolverParams& params, const Domain& domain)
    : params_(params),
      domain_(domain),
      poly6_(params.support()),
      spiky_(params.support()),
      grid_(params.support()) {
  const float d = params.spacing(), h = params.support(), r = params.particle_radius;
  mass_ = params.rest_density * d * d * d;
  // Calibrate ρ0 and S_0 on an interior point of the resting cubic lattice the emitter creates.
  double sum_w = poly6_.w_zero();
  core::for_each_lattice_point(d, h, [&](int i, int j, int k) {
    if (i || j || k) sum_w += poly6_.w_r2(d * d * float(i * i + j * j + k * k));
  });
  rho0_ = static_cast<float>(mass_ * sum_w);
  double s0 = 0.0;
  Vec3d grad_i = Vec3d::Zero();
  core::for_each_lattice_point(d, h, [&](int i, int j, int k) {
    if (!(i || j || k)) return;
    const Vec3f g = (mass_ / rho0_) * spiky_.grad(Vec3f(float(i), float(j), float(k)) * d);
    s0 += g.squaredNorm();
    grad_i += g.cast<double>();
  });
  s0 += grad_i.squaredNorm();
  s0_ = static_cast<float>(s0);
  epsilon_ = params.epsilon * s0_;
  w_dq_ = poly6_.w(params.scorr_dq * h);
  wall_lo_ = domain.min + Vec3f::Constant(r);
  wall_hi_ = domain.max - Vec3f::Constant(r);
}

std::size_t PbfSolver::scratch_bytes() const {
  return neighbors_.bytes() + grid_.bytes() + next_.capacity() * sizeof(Vec3f) + omega_.capacity() * sizeof(Vec3f) +
         reorder_scratch_.v3.capacity() * sizeof(Vec3f) + reorder_scratch_.u32.capacity() * sizeof(Index) +
         reorder_scratch_.u8.capacity() + reorder_scratch_.f32.capacity() * sizeof(float) + surface_tension_.bytes() +
         surface_candidates_.capacity() + clusters_.bytes() + pairs_.bytes() +
         lambda_c_.capacity() * sizeof(float);
}

void PbfSolver::search(ParticleSet& p) {
  grid_.build(p.position);
  // Re-sort by cell so that neighbours are close in memory; ids keep the identity of each particle.
  reorder(p, grid_.sorted(), reorder_scratch_);
  grid_.points_were_sorted();
  grid_.neighbors(p.position, neighbors_);
  // The Jacobi passes' cluster pairs, on the sorted positions (reused by every iteration of the sub-step).
  if (cluster_kernels_) {
    clusters_.assign(p.position, params_.spacing());
    core::build_cluster_pairs(clusters_, clusters_, params_.support(), pairs_, pair_scratch_);
  }
}

void PbfSolver::densities(std::span<const Vec3f> x, std::vector<float>& rho, std::uint8_t* candidates) const {
  using namespace core::simd;
  const float w0 = poly6_.w_zero(), m = mass_, k = poly6_.k;
  const Vec3f* xs = x.data();
  const __m128 h2 = broadcast(poly6_.h2), zero = _mm_setzero_ps();
  SurfaceTensionParams st;
  st.support = params_.support();
  // kClassify: also sum the neighbour offsets for the surface-tension classifier (METHOD.md §c.6).
  auto pass = [&](auto kClassify) {
    constexpr bool kC = decltype(kClassify)::value;
    parallel_for(static_cast<std::int64_t>(x.size()), [&](std::int64_t ii) {
      const auto i = static_cast<Index>(ii);
      const Vec3f xi = xs[i];
      const __m128 px = broadcast(xi.x()), py = broadcast(xi.y()), pz = broadcast(xi.z());
      __m128 sw = zero, ox = zero, oy = zero, oz = zero;
      const core::NeighborRange nb = neighbors_.of(i);
      for_neighbors4(nb, i, [&](const Index* j, __m128 lanes) {
        const V3 xj = gather(xs, j[0], j[1], j[2], j[3]);
        const __m128 rx = _mm_sub_ps(px, xj.x), ry = _mm_sub_ps(py, xj.y), rz = _mm_sub_ps(pz, xj.z);
        const __m128 r2 = _mm_add_ps(_mm_add_ps(_mm_mul_ps(rx, rx), _mm_mul_ps(ry, ry)), _mm_mul_ps(rz, rz));
        const __m128 q2 = _mm_sub_ps(h2, r2);
        sw = _mm_add_ps(sw, select(_mm_and_ps(lanes, _mm_cmplt_ps(r2, h2)), _mm_mul_ps(_mm_mul_ps(q2, q2), q2)));
        if constexpr (kC) {
          ox = _mm_add_ps(ox, select(lanes, rx));
          oy = _mm_add_ps(oy, select(lanes, ry));
          oz = _mm_add_ps(oz, select(lanes, rz));
        }
      });
      rho[i] = m * (w0 + k * hsum(sw));
      if constexpr (kC)
        candidates[i] = surface_candidate(nb.size(), Vec3f(hsum(ox), hsum(oy), hsum(oz)).norm(), st) ? 1 : 0;
    });
  };
  if (candidates)
    pass(std::true_type{});
  else
    pass(std::false_type{});
}

void PbfSolver::compute_densities(ParticleSet& p) {
  p.resize(p.size());
  search(p);
  densities(p.position, p.density);
}

namespace {

// The drag's parameters at this spacing (the CPU's pass and the GPU's constants, force_consts, both take these).
DragParams drag_params(const SolverParams& params, float mass) {
  DragParams dp;
  dp.scale = params.drag;
  dp.air_density = params.air_density;
  dp.liquid_density = params.rest_density;
  dp.spacing = params.spacing();
  dp.mass = mass;
  return dp;
}

// The surface tension's parameters at this spacing (the CPU's pass and the GPU's constants both take these).
SurfaceTensionParams surface_tension_params(const SolverParams& params, float mass) {
  SurfaceTensionParams st;
  // σ is given at the reference spacing d_ref = 0.05 m (SPlisHSPlasH's default radius, where the paper's
  // σ = 0.05 comes from) and scaled by (d/d_ref)², so the surface acceleration σκ/m ∝ 1/d keeps its size
  // relative to gravity at any resolution; the literal σ at d = 0.02 m pulls ~16× harder and jitters. The
  // surface layer's acceleration still grows as 1/d: the capillary sub-step (advance()) allows for it.
  const float dr = params.spacing() / SolverParams::kSurfaceTensionRefSpacing;
  st.sigma = params.surface_tension * dr * dr;
  st.samples_per_second = params.surface_tension_samples;
  st.support = params.support();
  st.mass = mass;
  return st;
}

}  // namespace

// a_ext = g + XSPH viscosity in the seed's acceleration form (eq. 12, sign fixed as METHOD.md §a.4):
//   a_vis,i = (η/Δt) Σ_j (m/ρ_j)(v_j − v_i) W(x_i − x_j, H_p)
// then surface tension (eq. 13) and drag (eq. 14), each skipped when its coefficient is 0.
void PbfSolver::external_accelerations(ParticleSet& p, float dt, double time) {
  const DragParams dp = drag_params(params_, mass_);
  const bool drag = params_.drag > 0.0f;
  // The drag's pass over the neighbours (occlusion) rides on the XSPH pass when there is one.
  const bool fused = drag && params_.viscosity > 0.0f;
  if (fused) {
    const DragModel model(dp);
    xsph_accelerations(p, dt, &model);
  } else {
    xsph_accelerations(p, dt, nullptr);
  }
  if (params_.surface_tension > 0.0f)
    surface_tension_.add_accelerations(p.position, p.id, neighbors_, surface_candidates_,
                                       surface_tension_params(params_, mass_), dt, surface_tension_step_key(time),
                                       p.acceleration);
  if (drag && !fused) add_drag(p.position, p.velocity, neighbors_, dp, p.acceleration);
}

// g + XSPH, and with `drag` also the drag acceleration (its occlusion term from the same pair loop).
void PbfSolver::xsph_accelerations(ParticleSet& p, float dt, const DragModel* drag) const {
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
  using namespace core::simd;
  const __m128 h2 = broadcast(poly6_.h2), zero = _mm_setzero_ps(), mk = broadcast(m * poly6_.k);
  auto pass = [&](auto kDrag) {
    constexpr bool kD = decltype(kDrag)::value;
    parallel_for(static_cast<std::int64_t>(p.size()), [&](std::int64_t ii) {
      const auto i = static_cast<Index>(ii);
      const Vec3f xi = x[i], vi = v[i];
      const __m128 px = broadcast(xi.x()), py = broadcast(xi.y()), pz = broadcast(xi.z());
      const __m128 ux = broadcast(vi.x()), uy = broadcast(vi.y()), uz = broadcast(vi.z());
      __m128 sx = zero, sy = zero, sz = zero, best = zero;
      Vec3f dir = Vec3f::Zero();
      if constexpr (kD) dir = DragModel::direction(vi);
      const __m128 dx = broadcast(dir.x()), dy = broadcast(dir.y()), dz = broadcast(dir.z());
      const core::NeighborRange nb = neighbors_.of(i);
      for_neighbors4(nb, i, [&](const Index* j, __m128 lanes) {
        const V3 xj = gather(x, j[0], j[1], j[2], j[3]);
        const V3 vj = gather(v, j[0], j[1], j[2], j[3]);
        const __m128 rx = _mm_sub_ps(px, xj.x), ry = _mm_sub_ps(py, xj.y), rz = _mm_sub_ps(pz, xj.z);
        const __m128 r2 = _mm_add_ps(_mm_add_ps(_mm_mul_ps(rx, rx), _mm_mul_ps(ry, ry)), _mm_mul_ps(rz, rz));
        const __m128 q2 = _mm_sub_ps(h2, r2);
        // (m/ρ_j) W_ij
        const __m128 wv = select(_mm_and_ps(lanes, _mm_cmplt_ps(r2, h2)),
                                 _mm_div_ps(_mm_mul_ps(mk, _mm_mul_ps(_mm_mul_ps(q2, q2), q2)), gather(rho, j[0], j[1], j[2], j[3])));
        sx = _mm_add_ps(sx, _mm_mul_ps(wv, _mm_sub_ps(vj.x, ux)));
        sy = _mm_add_ps(sy, _mm_mul_ps(wv, _mm_sub_ps(vj.y, uy)));
        sz = _mm_add_ps(sz, _mm_mul_ps(wv, _mm_sub_ps(vj.z, uz)));
        if constexpr (kD) best = DragModel::occlusion(best, dx, dy, dz, rx, ry, rz, r2, lanes);
      });
      a[i] = g + c * Vec3f(hsum(sx), hsum(sy), hsum(sz));
      if constexpr (kD) a[i] += drag->acceleration(vi, nb.size(), best);
    });
  };
  if (drag)
    pass(std::true_type{});
  else
    pass(std::false_type{});
}

void PbfSolver::clamp_to_walls(std::vector<Vec3f>& x) const {
  const Vec3f lo = wall_lo_, hi = wall_hi_;
  parallel_for(static_cast<std::int64_t>(x.size()), [&](std::int64_t i) { x[i] = x[i].cwiseMax(lo).cwiseMin(hi); });
}

// The two Jacobi passes run four neighbours at a time (sim/pair_loop.h). Lanes outside the support
// (a neighbour list is built on x at the start of the sub-step, the passes use x*) or at zero distance
// are masked off, which matches the scalar definitions: W and ∇W vanish at r ≥ h, ∇W is 0 at r = 0.
void PbfSolver::solve_iteration_lists(ParticleSet& p) {
  lambda_pass_lists(p);
  position_pass_lists(p);
}

void PbfSolver::lambda_pass_lists(ParticleSet& p) const {
  using namespace core::simd;
  const std::size_t n = p.size();
  const Vec3f* xs = p.predicted.data();
  float* lambda = p.lambda.data();
  float* rho = p.density.data();
  const float m = mass_, w0 = poly6_.w_zero(), rho0 = rho0_, eps = epsilon_;
  const __m128 h = broadcast(spiky_.h), h2 = broadcast(spiky_.h2), zero = _mm_setzero_ps();
  // ∇_j C_i = (m/ρ0) ∇W_ij with ∇W = kgrad (h − |r|)² r/|r|: one coefficient per pair times r.
  const __m128 cgrad = broadcast(mass_ / rho0_ * spiky_.kgrad);

  // λ_i from the density at x* (Poly6) and the constraint gradients (Spiky).
  parallel_for(static_cast<std::int64_t>(n), [&](std::int64_t ii) {
    const auto i = static_cast<Index>(ii);
    const Vec3f xi = xs[i];
    const __m128 px = broadcast(xi.x()), py = broadcast(xi.y()), pz = broadcast(xi.z());
    __m128 sw = zero, g2 = zero, gx = zero, gy = zero, gz = zero;
    for_neighbors4(neighbors_.of(i), i, [&](const Index* j, __m128 lanes) {
      const V3 xj = gather(xs, j[0], j[1], j[2], j[3]);
      const __m128 rx = _mm_sub_ps(px, xj.x), ry = _mm_sub_ps(py, xj.y), rz = _mm_sub_ps(pz, xj.z);
      const __m128 r2 = _mm_add_ps(_mm_add_ps(_mm_mul_ps(rx, rx), _mm_mul_ps(ry, ry)), _mm_mul_ps(rz, rz));
      const __m128 inside = _mm_and_ps(lanes, _mm_cmplt_ps(r2, h2));
      const __m128 q2 = _mm_sub_ps(h2, r2);
      sw = _mm_add_ps(sw, select(inside, _mm_mul_ps(_mm_mul_ps(q2, q2), q2)));
      const __m128 len = _mm_sqrt_ps(r2);
      const __m128 q = _mm_sub_ps(h, len);
      const __m128 c = select(_mm_and_ps(inside, _mm_cmpgt_ps(len, zero)),
                              _mm_div_ps(_mm_mul_ps(cgrad, _mm_mul_ps(q, q)), len));
      g2 = _mm_add_ps(g2, _mm_mul_ps(_mm_mul_ps(c, c), r2));  // |∇_j C_i|² = c² |r|²
      gx = _mm_add_ps(gx, _mm_mul_ps(c, rx));
      gy = _mm_add_ps(gy, _mm_mul_ps(c, ry));
      gz = _mm_add_ps(gz, _mm_mul_ps(c, rz));
    });
    rho[i] = m * (w0 + poly6_.k * hsum(sw));
    const Vec3f grad_i(hsum(gx), hsum(gy), hsum(gz));
    lambda[i] = pbf_lambda(density_constraint(rho[i], rho0), hsum(g2) + grad_i.squaredNorm(), eps);
  });
}

void PbfSolver::position_pass_lists(ParticleSet& p) {
  using namespace core::simd;
  const std::size_t n = p.size();
  const Vec3f* xs = p.predicted.data();
  const float* lambda = p.lambda.data();
  const __m128 h = broadcast(spiky_.h), h2 = broadcast(spiky_.h2), zero = _mm_setzero_ps();
  // Δx_i = (m/ρ0) Σ_j (λ_i + λ_j + s_corr) ∇W(x_i − x_j),  s_corr = −k (W/W(Δq))ⁿ / S_0.
  // The exponent is a compile-time constant in the loop (kN; 0 = no s_corr), so the power unrolls.
  const __m128 w_ratio = broadcast(poly6_.k / w_dq_), scorr_c = broadcast(-params_.scorr_k / s0_);
  const __m128 kgrad = broadcast(spiky_.kgrad), one = broadcast(1.0f);
  const float m_rho0 = mass_ / rho0_;
  const Vec3f lo = wall_lo_, hi = wall_hi_;
  // Jacobi: the corrected positions go to a second buffer, which then becomes x*.
  Vec3f* next = next_.data();
  auto positions = [&](auto kN) {
    constexpr int N = decltype(kN)::value;
    parallel_for(static_cast<std::int64_t>(n), [&](std::int64_t ii) {
      const auto i = static_cast<Index>(ii);
      const Vec3f xi = xs[i];
      const __m128 px = broadcast(xi.x()), py = broadcast(xi.y()), pz = broadcast(xi.z()), li = broadcast(lambda[i]);
      __m128 dx = zero, dy = zero, dz = zero;
      for_neighbors4(neighbors_.of(i), i, [&](const Index* j, __m128 lanes) {
        const V3 xj = gather(xs, j[0], j[1], j[2], j[3]);
        const __m128 rx = _mm_sub_ps(px, xj.x), ry = _mm_sub_ps(py, xj.y), rz = _mm_sub_ps(pz, xj.z);
        const __m128 r2 = _mm_add_ps(_mm_add_ps(_mm_mul_ps(rx, rx), _mm_mul_ps(ry, ry)), _mm_mul_ps(rz, rz));
        const __m128 len = _mm_sqrt_ps(r2);
        const __m128 use = _mm_and_ps(_mm_and_ps(lanes, _mm_cmplt_ps(r2, h2)), _mm_cmpgt_ps(len, zero));
        // 1/|r| depends only on r: dividing early keeps the division off the λ_j / s_corr chain.
        const __m128 inv_len = _mm_div_ps(one, len);
        __m128 l = _mm_add_ps(li, gather(lambda, j[0], j[1], j[2], j[3]));
        if constexpr (N > 0) {
          const __m128 q2 = _mm_sub_ps(h2, r2);
          const __m128 ratio = _mm_mul_ps(w_ratio, _mm_mul_ps(_mm_mul_ps(q2, q2), q2));
          l = _mm_add_ps(l, _mm_mul_ps(scorr_c, pow_int(ratio, N)));
        }
        const __m128 q = _mm_sub_ps(h, len);
        const __m128 c = select(use, _mm_mul_ps(_mm_mul_ps(_mm_mul_ps(l, kgrad), _mm_mul_ps(q, q)), inv_len));
        dx = _mm_add_ps(dx, _mm_mul_ps(c, rx));
        dy = _mm_add_ps(dy, _mm_mul_ps(c, ry));
        dz = _mm_add_ps(dz, _mm_mul_ps(c, rz));
      });
      next[i] = (xi + m_rho0 * Vec3f(hsum(dx), hsum(dy), hsum(dz))).cwiseMax(lo).cwiseMin(hi);
    });
  };
  const int sn = params_.scorr_k > 0.0f ? params_.scorr_n : 0;
  switch (sn) {  // validate() keeps n in [1, 8]
    case 0: positions(std::integral_constant<int, 0>{}); break;
    case 1: positions(std::integral_constant<int, 1>{}); break;
    case 2: positions(std::integral_constant<int, 2>{}); break;
    case 3: positions(std::integral_constant<int, 3>{}); break;
    case 4: positions(std::integral_constant<int, 4>{}); break;
    case 5: positions(std::integral_constant<int, 5>{}); break;
    case 6: positions(std::integral_constant<int, 6>{}); break;
    case 7: positions(std::integral_constant<int, 7>{}); break;
    default: positions(std::integral_constant<int, 8>{}); break;
  }
  p.predicted.swap(next_);
}

PbfLambdaConsts PbfSolver::lambda_consts() const {
  PbfLambdaConsts lk;
  lk.h = spiky_.h, lk.h2 = spiky_.h2, lk.poly6_k = poly6_.k, lk.w0 = poly6_.w_zero();
  lk.mass = mass_, lk.rho0 = rho0_, lk.epsilon = epsilon_;
  // ∇_j C_i = (m/ρ0) ∇W_ij with ∇W = kgrad (h − |r|)² r/|r|: one coefficient per pair times r.
  lk.cgrad = mass_ / rho0_ * spiky_.kgrad;
  return lk;
}

// Δx_i = (m/ρ0) Σ_j (λ_i + λ_j + s_corr) ∇W(x_i − x_j),  s_corr = −k (W/W(Δq))ⁿ / S_0.
PbfDeltaConsts PbfSolver::delta_consts() const {
  PbfDeltaConsts dk;
  dk.h = spiky_.h, dk.h2 = spiky_.h2, dk.kgrad = spiky_.kgrad, dk.w_ratio = poly6_.k / w_dq_;
  dk.scorr_c = -params_.scorr_k / s0_, dk.scorr_n = params_.scorr_k > 0.0f ? params_.scorr_n : 0;
  dk.m_rho0 = mass_ / rho0_, dk.lo = wall_lo_, dk.hi = wall_hi_;
  return dk;
}

// g + XSPH, air drag and surface tension as external_accelerations() applies them.
PbfForceConsts PbfSolver::force_consts(float dt) const {
  PbfForceConsts fk;
  fk.gravity = params_.gravity, fk.dt = dt, fk.xsph = params_.viscosity / dt, fk.mass_poly6_k = mass_ * poly6_.k;
  fk.vorticity = params_.vorticity;
  if (params_.drag > 0.0f) {
    const DragModel::Coefficients c = DragModel(drag_params(params_, mass_)).coefficients();
    fk.drag_L = c.L, fk.drag_y = c.y_coeff, fk.drag_re = c.re_coeff, fk.drag_d2 = c.d2, fk.drag_acc = c.acc;
  }
  if (params_.surface_tension > 0.0f) {
    const SurfaceTensionParams st = surface_tension_params(params_, mass_);
    fk.st_sigma = st.sigma, fk.st_samples_per_second = st.samples_per_second;
  }
  return fk;
}

// The alternative (PbfSolver::set_cluster_kernels): the two Jacobi passes on cluster pairs (sim/pbf_kernels.h): the list is built on x at the start of the
// sub-step, the passes use x*, and lanes outside the support or at zero distance are masked, which matches the
// scalar definitions: W and ∇W vanish at r ≥ h, ∇W is 0 at r = 0.
void PbfSolver::solve_iteration(ParticleSet& p) {
  if (!cluster_kernels_) return solve_iteration_lists(p);
  clusters_.update(p.predicted);
  lambda_c_.resize(clusters_.padded());
  const PbfLambdaConsts lk = lambda_consts();
  const auto nc = static_cast<std::int64_t>(clusters_.clusters);
  core::parallel_blocks(nc, kClusterBlock, [&](std::int64_t b, std::int64_t e) {
    pbf_lambda_clusters(clusters_, pairs_, lk, p.density.data(), lambda_c_.data(), static_cast<std::size_t>(b),
                        static_cast<std::size_t>(e));
  });
  // Δx_i = (m/ρ0) Σ_j (λ_i + λ_j + s_corr) ∇W(x_i − x_j),  s_corr = −k (W/W(Δq))ⁿ / S_0.
  const PbfDeltaConsts dk = delta_consts();
  // Jacobi: the corrected positions go to a second buffer, which then becomes x*.
  core::parallel_blocks(nc, kClusterBlock, [&](std::int64_t b, std::int64_t e) {
    pbf_delta_clusters(clusters_, pairs_, lambda_c_.data(), dk, next_.data(), static_cast<std::size_t>(b),
                       static_cast<std::size_t>(e));
  });
  p.predicted.swap(next_);
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
  StepView view{dt, time, -1, params_.iterations, params_.particle_radius, &neighbors_};
  {
    core::ScopedTimer t(times.neighbors);
    p.resize(n);
    next_.resize(n);
    search(p);
  }
  {
    core::ScopedTimer t(times.forces);
    if (params_.surface_tension > 0.0f) {
      surface_candidates_.resize(n);
      densities(p.position, p.density, surface_candidates_.data());
    } else {
      densities(p.position, p.density);
    }
    external_accelerations(p, dt, time);
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
    Vec3f* shift = p.shift.data();
    parallel_for(static_cast<std::int64_t>(n), [&](std::int64_t i) {
      const Vec3f vs = v[i] + dt * a[i];
      xs[i] = (x[i] + dt * vs).cwiseMax(lo).cwiseMin(hi);
      shift[i] = Vec3f::Zero();
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
    const Vec3f* shift = p.shift.data();
    parallel_for(static_cast<std::int64_t>(n), [&](std::int64_t i) { v[i] = (xs[i] - x[i] - shift[i]) * inv_dt; });
    if (params_.vorticity > 0.0f) vorticity_confinement(p, dt);
    p.position.swap(p.predicted);
  }
  {
    core::ScopedTimer t(times.control);
    view.iteration = -1;
    controller.end_step(view, p);
    controller.emit(view, p);
  }
}

SubstepPlan plan_substeps(const SolverParams& params, double max_speed, double frame_dt) {
  const double v_est = max_speed + params.gravity.norm() * frame_dt;
  // and at most the capillary condition's sub-step (explicit surface tension is unstable above it).
  const double dt_cfl =
      std::min(double(cfl_dt(static_cast<float>(v_est), params.spacing(), params.cfl, params.max_dt)), params.capillary_dt());
  SubstepPlan plan;
  plan.steps = std::max(static_cast<int>(std::ceil(frame_dt / dt_cfl - 1e-9)), 1);
  if (plan.steps > params.max_substeps) {
    plan.steps = params.max_substeps;
    plan.capped = true;
  }
  plan.dt = static_cast<float>(frame_dt / plan.steps);
  return plan;
}

Result<FrameStats> PbfSolver::advance(ParticleSet& p, double time, double frame_dt, Controller& controller) {
  FrameStats stats;
  const auto n = static_cast<std::int64_t>(p.size());
  // Sub-step from the CFL condition on the fastest particle, allowing for gravity's speed-up over the frame.
  const double vmax = std::sqrt(core::deterministic_max(n, 0.0, [&](std::int64_t i) {
    return static_cast<double>(p.velocity[static_cast<std::size_t>(i)].squaredNorm());
  }));
  const SubstepPlan plan = plan_substeps(params_, vmax, frame_dt);
  const int steps = plan.steps;
  const float dt = plan.dt;
  stats.substeps_capped = plan.capped;
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
    return core::deterministic_max(static_cast<std::int64_t>(p.size()), 0.0, [&](std::int64_t i) {
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
  const auto m = static_cast<std::int64_t>(p.size());  // a controller may have added particles (Controller::emit)

  // Density error at the end of the frame, from the densities of the last iteration.
  const float rho0 = rho0_;
  stats.density_error_mean = m ? core::deterministic_sum(m, [&](std::int64_t i) {
    return static_cast<double>(density_constraint(p.density[static_cast<std::size_t>(i)], rho0));
  }) / double(m) : 0.0;
  stats.density_error_max = core::deterministic_max(m, 0.0, [&](std::int64_t i) {
    return static_cast<double>(density_constraint(p.density[static_cast<std::size_t>(i)], rho0));
  });
  stats.max_speed = std::sqrt(core::deterministic_max(m, 0.0, [&](std::int64_t i) {
    return static_cast<double>(p.velocity[static_cast<std::size_t>(i)].squaredNorm());
  }));
  return stats;
}

}  // namespace ff::sim
