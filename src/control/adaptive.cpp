#include "control/adaptive.h"

#include "core/pair_loop.h"
#include "core/parallel.h"
#include "core/simd.h"
#include "sampling/weights.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>

namespace ff::control {
using core::parallel_for;
namespace {

// Lanes of four fluid particles that belong to target t: pairs of another target are masked off (tested only in a
// multi-target scene; one target needs no test).
inline __m128 same_target(const std::uint8_t* tf, const Index* j, std::uint8_t t) {
  return _mm_castsi128_ps(
      _mm_setr_epi32(tf[j[0]] == t ? -1 : 0, tf[j[1]] == t ? -1 : 0, tf[j[2]] == t ? -1 : 0, tf[j[3]] == t ? -1 : 0));
}

// |p − x_j|² for four fluid particles j (p broadcast in px, py, pz).
inline __m128 dist2(const Vec3f* x, const Index* j, __m128 px, __m128 py, __m128 pz) {
  const core::simd::V3 xj = core::simd::gather(x, j[0], j[1], j[2], j[3]);
  const __m128 rx = _mm_sub_ps(px, xj.x), ry = _mm_sub_ps(py, xj.y), rz = _mm_sub_ps(pz, xj.z);
  return _mm_add_ps(_mm_add_ps(_mm_mul_ps(rx, rx), _mm_mul_ps(ry, ry)), _mm_mul_ps(rz, rz));
}

// Four packed samples, transposed: one register each for x, y, z and the per-pass value w.
struct P4 {
  __m128 x, y, z, w;
};
inline P4 gather_packed(const PackedSample* s, const Index* k) {
  __m128 a = _mm_load_ps(&s[k[0]].x), b = _mm_load_ps(&s[k[1]].x), c = _mm_load_ps(&s[k[2]].x),
         d = _mm_load_ps(&s[k[3]].x);
  _MM_TRANSPOSE4_PS(a, b, c, d);
  return {a, b, c, d};
}

// The sample-major passes that feed the bond transpose (the fill pass counts each fluid particle's bonds per
// thread, the placement writes them) split the samples the same way: T contiguous ranges in order, so a particle's
// bonds come out in ascending sample order for any thread count.
int bond_threads(std::size_t m) { return static_cast<std::int64_t>(m) < core::kMinParallel ? 1 : core::thread_count(); }
void sample_range(std::size_t m, int T, int t, std::size_t& b, std::size_t& e) {
  const std::size_t chunk = (m + static_cast<std::size_t>(T) - 1) / static_cast<std::size_t>(T);
  b = std::min(m, chunk * static_cast<std::size_t>(t));
  e = std::min(m, b + chunk);
}

// Where the padding of the bond lists points: far from any fluid (r² ≈ 3e36, still finite), with w = 0.
constexpr float kSentinelCoord = 1e18f;

}  // namespace

AdaptiveController::AdaptiveController(const ControlContext& ctx, const AdaptiveParams& params, float hc)
    : ctx_(ctx), params_(params), hc_(hc), d_(ctx.spacing()), poly6_(hc), spiky_(hc), fluid_grid_(hc) {}

Result<std::unique_ptr<AdaptiveController>> AdaptiveController::create(std::vector<ControlTarget> targets,
                                                                        const ControlContext& ctx,
                                                                        const AdaptiveParams& params) {
  FF_CHECK(params.validate());
  ControlSamples samples;
  FF_CHECK(samples.init(std::move(targets), "adaptive",
                        {.cell_order = true, .weights = params.weights, .normals = true, .velocities = true}));
  std::unique_ptr<AdaptiveController> c(new AdaptiveController(ctx, params, samples.hc));
  c->samples_ = std::move(samples);
  const float d = ctx.spacing();
  // ε_c = epsilon · S_0 with ρ_ref the lattice's kernel-sum density at H_c: what a filled interior sample sees
  // (METHOD §a.3).
  const double rho_ref = sampling::lattice_density(d, c->hc_, ctx.rest_density);
  const double s0 = full_gradient_sum(d, c->hc_, ctx.particle_mass, rho_ref);
  c->eps_c_ = static_cast<float>(params.epsilon * s0);
  c->fill_.assign(c->samples_.size(), 0.0f);
  c->speed_scale_ = speed_scales(c->samples_.target, c->samples_.targets(), params.speed_reference);
  // The gather field covers the domain at the control support (coarser on a huge domain).
  c->seed_field_.resize(c->samples_.targets());
  for (auto& f : c->seed_field_) f.reset(ctx.domain.min, ctx.domain.max, c->hc_);
  return c;
}

void AdaptiveController::set_target_pose(std::size_t target, const pose::Pose& pose) { samples_.set_target_pose(target, pose); }

// The bond masks hold a byte per group of four pairs, one bit per pair.
template <class F>
void AdaptiveController::for_each_bond(std::size_t i, F&& f) const {
  const core::NeighborRange r = cf_.of(i);
  const std::uint8_t* mask = bond_mask_.data() + mask_group_start_[i];
  for (Index g = 0, groups = mask_group_start_[i + 1] - mask_group_start_[i]; g < groups; ++g)
    for (unsigned bits = mask[g]; bits; bits &= bits - 1) f(r[4 * g + static_cast<std::size_t>(__builtin_ctz(bits))]);
}

void AdaptiveController::begin_step(const sim::StepView& view, sim::ParticleSet& p) {
  time_ = view.time;
  // A target whose mesh is swapped at this time (morph A → B) takes its next sample set: its fluid stays, and
  // the new samples pull it into the new shape.
  // u_c over this sub-step (forward difference): moving targets carry their fluid along (AdaptiveParams::follow).
  if (samples_.update(view.time, view.dt)) {
    fill_.assign(samples_.size(), 0.0f);
    speed_scale_ = speed_scales(samples_.target, samples_.targets(), params_.speed_reference);
  }
  // After the swap: which targets move is the new set's from its first sub-step on (as on the device).
  update_strengths();
  const std::size_t n = p.size(), m = samples_.position.size();
  // Control–fluid pairs within H_c, one query per sub-step on the positions at its start (samples → fluid); the
  // fluid → sample bonds are its transpose, built below.
  fluid_grid_.build(p.position);
  fluid_grid_.query(p.position, samples_.position, hc_, cf_);
  nearest_.resize(n);
  fill_.resize(m);
  bond_radius2_.resize(m);
  sample_xw_.resize(m + 1);
  sample_xw_[m] = {kSentinelCoord, kSentinelCoord, kSentinelCoord, 0.0f};
  lambda_.assign(m, 0.0f);

  fill_samples(p);
  build_bonds(p);
  // The bonds, fills and nearest samples are decided at the start of the sub-step (fluid at x, samples at their
  // pose then); the corrections act on x*, where the fluid is at its end, so they see the samples where they are at
  // its end too: x_c + Δt u_c, the pose at t + Δt. Otherwise a moving target's samples trail the fluid they carry by
  // u_c Δt, and its density constraint pulls that fluid back.
  if (samples_.moving())
    parallel_for(static_cast<std::int64_t>(m), [&](std::int64_t ii) {
      const auto i = static_cast<std::size_t>(ii);
      const Vec3f end = samples_.position[i] + view.dt * samples_.velocity[i];
      sample_xw_[i].x = end.x(), sample_xw_[i].y = end.y(), sample_xw_[i].z = end.z();
    });
}

void AdaptiveController::update_strengths() {
  // Every part of the control scales with its target's strength (1: as written; 0: the target is inactive, below).
  strength_.resize(samples_.targets());
  softened_ = false;
  target_moving_.resize(samples_.targets());
  for (std::size_t t = 0; t < strength_.size(); ++t) {
    strength_[t] = samples_.strength(static_cast<std::uint8_t>(t), time_);
    softened_ = softened_ || (strength_[t] > 0.0f && strength_[t] < 1.0f);
    target_moving_[t] = samples_.moving(static_cast<std::uint8_t>(t)) ? 1 : 0;
  }
}

void AdaptiveController::fill_samples(const sim::ParticleSet& p) {
  const std::size_t n = p.size(), m = samples_.position.size();
  const Vec3f* x = p.position.data();
  const std::uint8_t* tf = p.target.data();
  // ρ_p,i (eq. 8) at x, the fill ratio and the bond radius H_c*,i (eq. 19).
  using namespace core::simd;
  const float mp = ctx_.particle_mass, hc2 = hc_ * hc_;
  const bool multi = samples_.mass.size() > 1;
  const __m128 h2 = broadcast(poly6_.h2), hc2v = broadcast(hc2), zero = _mm_setzero_ps();
  // Groups of four pairs per sample: where each sample's bond masks start.
  mask_group_start_.resize(m + 1);
  mask_group_start_[0] = 0;
  for (std::size_t i = 0; i < m; ++i) mask_group_start_[i + 1] = mask_group_start_[i] + static_cast<Index>((cf_.of(i).size() + 3) / 4);
  bond_mask_.resize(mask_group_start_[m]);
  const auto fill_sample = [&](std::size_t i) {
    float rho = 0.0f;
    const std::uint8_t t = samples_.target[i];
    std::uint8_t* mask = bond_mask_.data() + mask_group_start_[i];
    if (!active(t, time_)) {
      std::fill(mask, mask + (mask_group_start_[i + 1] - mask_group_start_[i]), std::uint8_t(0));
    } else {
      const Vec3f xi = samples_.position[i];
      const __m128 px = broadcast(xi.x()), py = broadcast(xi.y()), pz = broadcast(xi.z());
      __m128 sw = zero;
      std::size_t g = 0;
      // With the bond masks for H_c*,i = H_c (r ≤ H_c), right for every sample that is not over-full, which is
      // nearly all of them once formed; the others are masked again below.
      core::for_neighbors4(cf_.of(i), 0, [&](const Index* j, __m128 lanes) {
        const __m128 r2 = dist2(x, j, px, py, pz);
        __m128 same = lanes;
        if (multi) same = _mm_and_ps(same, same_target(tf, j, t));
        const __m128 use = _mm_and_ps(same, _mm_cmplt_ps(r2, h2));
        const __m128 q2 = _mm_sub_ps(h2, r2);
        sw = _mm_add_ps(sw, select(use, _mm_mul_ps(_mm_mul_ps(q2, q2), q2)));
        mask[g++] = static_cast<std::uint8_t>(_mm_movemask_ps(_mm_and_ps(same, _mm_cmple_ps(r2, hc2v))));
      });
      rho = poly6_.k * hsum(sw);
    }
    const float f = mp * rho / samples_.rho_c[i];
    fill_[i] = f;
    sample_xw_[i] = {samples_.position[i].x(), samples_.position[i].y(), samples_.position[i].z(), f};
    float scale = 1.0f;
    if (params_.bond_breaking) {
      scale = params_.bond_radius == BondRadius::Paper ? 1.0f / (1.0f + f) : std::min(1.0f, 2.0f / (1.0f + f));
    }
    const float hs2 = hc2 * scale * scale;
    bond_radius2_[i] = hs2;
    // Bond masks, one bit per pair: r ≤ H_c*,i (and the same target). The pairs are still in L1 from the sum.
    if (!active(t, time_) || hs2 == hc2) return;
    const Vec3f xi = samples_.position[i];
    const __m128 px = broadcast(xi.x()), py = broadcast(xi.y()), pz = broadcast(xi.z()), hs = broadcast(hs2);
    std::size_t g = 0;
    core::for_neighbors4(cf_.of(i), 0, [&](const Index* j, __m128 lanes) {
      const __m128 r2 = dist2(x, j, px, py, pz);
      __m128 use = _mm_and_ps(lanes, _mm_cmple_ps(r2, hs));
      if (multi) use = _mm_and_ps(use, same_target(tf, j, t));
      mask[g++] = static_cast<std::uint8_t>(_mm_movemask_ps(use));
    });
  };
  // Each thread fills its range of samples and counts their bonds per fluid particle (build_bonds places them).
  const int T = bond_threads(m);
  cursor_.assign(static_cast<std::size_t>(T) * n, 0);
#pragma omp parallel num_threads(T)
  {
    const int t = omp_get_thread_num();
    Index* count = cursor_.data() + static_cast<std::size_t>(t) * n;
    std::size_t b, e;
    sample_range(m, T, t, b, e);
    for (std::size_t i = b; i < e; ++i) {
      fill_sample(i);
      for_each_bond(i, [&](Index j) { ++count[j]; });
    }
  }
}

// Bonds B(j), CSR over the fluid, as the transpose of the sample → fluid pairs with |x_ci − x_j| ≤ H_c*,i: a
// counting sort in which thread t counts (in the fill pass) and then places the bonds of its contiguous range of
// samples. Within a particle, bonds are in ascending sample order for any thread count (thread ranges are
// ordered), so the result is thread-count invariant. A fluid particle is controlled iff it has a bond (METHOD §a.5).
void AdaptiveController::build_bonds(sim::ParticleSet& p) {
  const std::size_t n = p.size(), m = samples_.position.size();
  const Vec3f* x = p.position.data();
  const int T = bond_threads(m);  // the fill pass's partition: cursor_ holds its counts per thread
  bond_off_.resize(n + 1);
  bond_end_.resize(n);
  Index run = 0;
  for (std::size_t j = 0; j < n; ++j) {
    bond_off_[j] = run;
    for (int t = 0; t < T; ++t) {
      Index& c = cursor_[static_cast<std::size_t>(t) * n + j];
      const Index k = c;
      c = run;
      run += k;
    }
    bond_end_[j] = run;
    run = bond_off_[j] + ((run - bond_off_[j] + 3) & ~Index(3));  // room for the padding
  }
  bond_off_[n] = run;
  bond_idx_.resize(run);
#pragma omp parallel num_threads(T)
  {
    const int t = omp_get_thread_num();
    Index* cursor = cursor_.data() + static_cast<std::size_t>(t) * n;
    std::size_t b, e;
    sample_range(m, T, t, b, e);
    for (std::size_t i = b; i < e; ++i)
      for_each_bond(i, [&](Index j) { bond_idx_[cursor[j]++] = static_cast<Index>(i); });
  }

  // The padding, then the nearest bonded sample of each particle (ties: the lower sample index), four bonds at a
  // time.
  using namespace core::simd;
  Index* bound = p.bound_control.data();
  const auto sentinel = static_cast<Index>(m);
  parallel_for(static_cast<std::int64_t>(n), [&](std::int64_t jj) {
    const auto j = static_cast<std::size_t>(jj);
    const Index b = bond_off_[j], e = bond_off_[j + 1];
    if (b == e) {
      nearest_[j] = bound[j] = kInvalidIndex;
      return;
    }
    for (Index k = bond_end_[j]; k < e; ++k) bond_idx_[k] = sentinel;
    const Vec3f xj = x[j];
    const __m128 px = broadcast(xj.x()), py = broadcast(xj.y()), pz = broadcast(xj.z());
    __m128 best = broadcast(INFINITY);
    __m128i best_i = _mm_set1_epi32(-1);
    for (Index k = b; k < e; k += 4) {
      // The padding is far away: it never beats a real bond, and every list has one.
      const Index* g = bond_idx_.data() + k;
      const Index i0 = g[0], i1 = g[1], i2 = g[2], i3 = g[3];
      const P4 xc = gather_packed(sample_xw_.data(), g);
      const __m128 rx = _mm_sub_ps(xc.x, px), ry = _mm_sub_ps(xc.y, py), rz = _mm_sub_ps(xc.z, pz);
      const __m128 r2 = _mm_add_ps(_mm_add_ps(_mm_mul_ps(rx, rx), _mm_mul_ps(ry, ry)), _mm_mul_ps(rz, rz));
      // Bonds ascend, so a strict < keeps the lower index of a tie within a lane.
      const __m128 better = _mm_cmplt_ps(r2, best);
      best = _mm_blendv_ps(best, r2, better);
      best_i = _mm_castps_si128(_mm_blendv_ps(_mm_castsi128_ps(best_i),
                                              _mm_castsi128_ps(_mm_setr_epi32(static_cast<int>(i0), static_cast<int>(i1),
                                                                              static_cast<int>(i2), static_cast<int>(i3))),
                                              better));
    }
    alignas(16) float r2s[4];
    alignas(16) Index is[4];
    _mm_store_ps(r2s, best);
    _mm_store_si128(reinterpret_cast<__m128i*>(is), best_i);
    std::size_t l = 0;
    for (std::size_t k = 1; k < 4; ++k)
      if (r2s[k] < r2s[l] || (r2s[k] == r2s[l] && is[k] < is[l])) l = k;
    nearest_[j] = is[l];
    bound[j] = samples_.original[is[l]];
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
    const float thr = params_.normal_threshold * samples_.g_ref;
    parallel_for(static_cast<std::int64_t>(n), [&](std::int64_t jj) {
      const auto j = static_cast<std::size_t>(jj);
      const Index i = nearest_[j];
      if (i == kInvalidIndex) return;
      const Vec3f nrm = samples_.normal[i];
      const float len = nrm.norm();
      if (!(len >= thr) || len == 0.0f) return;
      const Vec3f nh = nrm / len;
      const float out = nh.dot(a[j]);
      if (out > 0.0f) a[j] -= (softened_ ? strength_[p.target[j]] : 1.0f) * out * nh;
    });
  }
  // Speed limit of controlled fluid: v* = v + Δt a is brought back to max_speed through the acceleration. On a
  // moving target, v* is first pulled toward the pose velocity u_c of the particle's nearest bonded sample, and the
  // limit holds for v* − u_c: fluid is carried along with the moving shape, at any speed of the shape.
  {
    const float vmax_ref = params_.max_speed * d_, dt = view.dt;
    const Vec3f* v = p.velocity.data();
    const bool follow = samples_.moving() && params_.follow > 0.0f;
    const float k = std::min(1.0f, params_.follow * dt / kReferenceDt);
    parallel_for(static_cast<std::int64_t>(n), [&](std::int64_t jj) {
      const auto j = static_cast<std::size_t>(jj);
      if (bond_off_[j] == bond_off_[j + 1]) return;
      const float vmax = vmax_ref * speed_of(p.target[j]);
      if (follow && target_moving_[p.target[j]]) {  // a static target's fluid (u_c = 0) is not damped
        const float s = softened_ ? strength_[p.target[j]] : 1.0f;
        const Vec3f u = samples_.velocity[nearest_[j]];
        a[j] += (s * k / dt) * (u - (v[j] + dt * a[j]));
        const Vec3f vs = v[j] + dt * a[j] - u;
        const float s2 = vs.squaredNorm();
        if (s2 > vmax * vmax) a[j] += s * (vs * (vmax / std::sqrt(s2)) - vs) / dt;
        return;
      }
      const Vec3f vs = v[j] + dt * a[j];
      const float s2 = vs.squaredNorm();
      if (s2 > vmax * vmax) a[j] += (softened_ ? strength_[p.target[j]] : 1.0f) * (vs * (vmax / std::sqrt(s2)) - vs) / dt;
    });
  }
  if (params_.gather) gather(p);
}

// Gather (ours, METHOD §a.10): an unbonded particle whose target still has under-filled samples is steered
// toward the nearest of them, at a limited speed, with gravity cancelled so it can rise into a target
// above it. It stops as soon as the particle is bonded (the control takes over) or the target is full.
void AdaptiveController::gather(sim::ParticleSet& p) {
  const std::size_t n = p.size(), m = samples_.position.size();
  // Which targets have unbonded fluid at all (once formed, none: the field is not worth computing).
  std::vector<char> wanted(seed_field_.size(), 0);
  for (std::size_t j = 0; j < n; ++j)
    if (p.target[j] < wanted.size() && bond_off_[j] == bond_off_[j + 1]) wanted[p.target[j]] = 1;
  for (std::size_t t = 0; t < seed_field_.size(); ++t) {
    seeds_.clear();
    if (wanted[t] && active(static_cast<std::uint8_t>(t), time_))
      for (std::size_t i = 0; i < m; ++i)
        if (samples_.target[i] == t && fill_[i] < params_.gather_fill) seeds_.push_back(static_cast<Index>(i));
    seed_field_[t].compute(samples_.position, seeds_);
  }
  const float speed_ref = params_.gather_speed * d_, inv_tau = 1.0f / params_.gather_time;
  // On a moving target the seed moves too: the steering velocity adds the seed's pose velocity (see follow), so fluid
  // shed by a fast limb catches up with it instead of chasing where it was, and closes in at least at a share of that
  // speed (gather_chase): at gather_speed alone it never caught a limb swinging ten times faster.
  const bool chase = samples_.moving() && params_.follow > 0.0f;
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
    const Vec3f to = samples_.position[s] - x[j];
    const float len = to.norm();
    if (len <= 0.0f) return;
    const float speed = speed_ref * speed_of(t);
    Vec3f v_des;
    if (chase) {  // closing in at least at a share of the seed's own speed, on top of following it
      const Vec3f& u = samples_.velocity[s];
      v_des = (std::max(speed, params_.gather_chase * u.norm()) / len) * to + u;
    } else {
      v_des = (speed / len) * to;
    }
    const Vec3f da = -g + inv_tau * (v_des - v[j]);
    a[j] += softened_ ? strength_[t] * da : da;
  });
}

// Eq. 17–18 as METHOD §a.5: a soft spring toward the bonded samples, stiffness f_i(r) = 1/(1 + (ρ_p/ρ_c) r/H_c),
// kernel-averaged so symmetric surroundings pull ~nothing. Once per sub-step.
void AdaptiveController::adaptive_spring(sim::ParticleSet& p, float dt) const {
  using namespace core::simd;
  const std::size_t n = p.size();
  Vec3f* xs = p.predicted.data();
  const float gamma = params_.gamma * std::min(1.0f, dt / kReferenceDt);
  Vec3f* shift = p.shift.data();
  const bool kinematic = params_.kinematic;
  const __m128 h2 = broadcast(poly6_.h2), inv_hc = broadcast(1.0f / hc_), one = broadcast(1.0f), zero = _mm_setzero_ps();
  parallel_for(static_cast<std::int64_t>(n), [&](std::int64_t jj) {
    const auto j = static_cast<std::size_t>(jj);
    const Index b = bond_off_[j], e = bond_off_[j + 1];
    if (b == e) return;
    const Vec3f xj = xs[j];
    const __m128 px = broadcast(xj.x()), py = broadcast(xj.y()), pz = broadcast(xj.z());
    __m128 nx = zero, ny = zero, nz = zero, den = zero;
    // Four bonds at a time: Σ w f r and Σ w with w the Poly6 weight (its constant cancels in the ratio).
    for (Index k = b; k < e; k += 4) {
      // w of the packed samples is their fill ratio here (written by begin_step); the padding is out of reach.
      const P4 xc = gather_packed(sample_xw_.data(), bond_idx_.data() + k);
      const __m128 rx = _mm_sub_ps(xc.x, px), ry = _mm_sub_ps(xc.y, py), rz = _mm_sub_ps(xc.z, pz);
      const __m128 r2 = _mm_add_ps(_mm_add_ps(_mm_mul_ps(rx, rx), _mm_mul_ps(ry, ry)), _mm_mul_ps(rz, rz));
      const __m128 q2 = _mm_sub_ps(h2, r2);
      const __m128 w = select(_mm_cmplt_ps(r2, h2), _mm_mul_ps(_mm_mul_ps(q2, q2), q2));
      const __m128 fill = xc.w;
      const __m128 f = _mm_div_ps(one, _mm_add_ps(one, _mm_mul_ps(fill, _mm_mul_ps(_mm_sqrt_ps(r2), inv_hc))));
      const __m128 wf = _mm_mul_ps(w, f);
      nx = _mm_add_ps(nx, _mm_mul_ps(wf, rx));
      ny = _mm_add_ps(ny, _mm_mul_ps(wf, ry));
      nz = _mm_add_ps(nz, _mm_mul_ps(wf, rz));
      den = _mm_add_ps(den, w);
    }
    const float d = hsum(den);
    if (d > 0.0f) {
      const float g = softened_ ? gamma * strength_[p.target[j]] : gamma;
      const Vec3f dx = (g / d) * Vec3f(hsum(nx), hsum(ny), hsum(nz));
      xs[j] = xj + dx;
      if (kinematic) shift[j] += dx;
    }
  });
}

// Eq. 6–10 (METHOD §a.3): per sample λ_i = −C_i/(Σ_j |g_ij|² + ε_c) with C_i = min(ρ_p,i/ρ_c,i − 1, 0) at x*,
// g_ij = −(m_p/ρ_c,i) ∇W(x_ci − x*_j); per fluid particle Δx_j = α Σ_{i∈B(j)} φ̃_i λ_i g_ij, at most clamp·d.
void AdaptiveController::control_correction(sim::ParticleSet& p, float dt) {
  if (p.size() == 0) return;
  sample_lambdas(p);
  if (std::getenv("FF_DEBUG_ACTIVE")) print_active_set();
  if (active_.empty()) return;  // every sample is full: no correction anywhere
  // The clamp in spacings, × each target's speed factor (at most one spacing), × Δt/Δt_ref.
  max_dx_.resize(samples_.targets());
  for (std::size_t t = 0; t < max_dx_.size(); ++t)
    max_dx_[t] = std::min(1.0f, params_.clamp * speed_scale_[t]) * d_ * std::min(1.0f, dt / kReferenceDt);
  const CorrectionLimit limit{params_.alpha, max_dx_.data(), max_dx_.size(), params_.kinematic};
  // Once a target has formed only a few (surface) samples are still under-filled: then the sum is scattered from
  // those samples, instead of every fluid particle walking its ~270 bonds to find them.
  if (active_.size() * 8 < samples_.position.size()) scatter_correction(p, limit);
  else gather_correction(p, limit);
}

// λ per sample, four fluid neighbours at a time (core/pair_loop.h; padding lanes point at particle 0, masked),
// and the sample's coefficient φ̃ λ m_p/ρ_c kg of the Δx pass (0 when full) into its packed w; active_ lists the
// samples with λ > 0.
void AdaptiveController::sample_lambdas(sim::ParticleSet& p) {
  using namespace core::simd;
  const std::size_t m = samples_.position.size();
  const Vec3f* xs = p.predicted.data();
  const std::uint8_t* tf = p.target.data();
  const float mp = ctx_.particle_mass, eps = eps_c_;
  const bool multi = samples_.mass.size() > 1;
  const __m128 h = broadcast(spiky_.h), h2 = broadcast(poly6_.h2), zero = _mm_setzero_ps();
  const float kg = -spiky_.kgrad;  // > 0: −∇W(r) = kg (h − |r|)² r̂ points along r = x_c − x_p (attraction)
  parallel_for(static_cast<std::int64_t>(m), [&](std::int64_t ii) {
    const auto i = static_cast<std::size_t>(ii);
    lambda_[i] = 0.0f;
    sample_xw_[i].w = 0.0f;
    const std::uint8_t t = samples_.target[i];
    if (!active(t, time_)) return;
    const PackedSample xi = sample_xw_[i];  // at the end of the sub-step, as x* (begin_step)
    const __m128 px = broadcast(xi.x), py = broadcast(xi.y), pz = broadcast(xi.z);
    const auto range = cf_.of(i);
    // Density and gradient sums in one pass over the pairs: once the fluid has arrived nearly every sample is
    // slightly under-filled (the control holds the fluid against the PBF pressure), so the gradient sum is needed
    // almost everywhere and a second pass would decode and gather every pair again.
    __m128 sw = zero, g2 = zero;
    core::for_neighbors4(range, 0, [&](const Index* j, __m128 lanes) {
      const __m128 r2 = dist2(xs, j, px, py, pz);
      __m128 use = _mm_and_ps(lanes, _mm_cmplt_ps(r2, h2));
      if (multi) use = _mm_and_ps(use, same_target(tf, j, t));
      const __m128 q2 = _mm_sub_ps(h2, r2);
      sw = _mm_add_ps(sw, select(use, _mm_mul_ps(_mm_mul_ps(q2, q2), q2)));
      const __m128 q = _mm_sub_ps(h, _mm_sqrt_ps(r2));
      const __m128 qq = _mm_mul_ps(q, q);
      g2 = _mm_add_ps(g2, select(use, _mm_mul_ps(qq, qq)));  // |∇W|² = kgrad² (h − r)⁴
    });
    const float c = mp * poly6_.k * hsum(sw) / samples_.rho_c[i] - 1.0f;
    if (c >= 0.0f) return;
    const float k = mp / samples_.rho_c[i] * spiky_.kgrad;
    lambda_[i] = -c / (k * k * hsum(g2) + eps);
    sample_xw_[i].w = strength_[t] * samples_.phi[i] * lambda_[i] * mp / samples_.rho_c[i] * kg;
  });
  active_.clear();
  for (std::size_t i = 0; i < m; ++i)
    if (lambda_[i] > 0.0f) active_.push_back(static_cast<Index>(i));
}

// FF_DEBUG_ACTIVE=1: the active set of every iteration on stderr (bench/RESULTS.md, "Where the formed frame's time
// goes"): how many samples have λ > 0, how many were under-filled at the start of the sub-step, and how many
// started clearly over-full (ρ_p/ρ_c ≥ 1.05), the ones an active-set rule with a 5 % margin could skip.
void AdaptiveController::print_active_set() const {
  const std::size_t m = samples_.position.size();
  std::size_t under = 0, over = 0, over_active = 0;
  for (std::size_t i = 0; i < m; ++i) {
    under += fill_[i] < 1.0f;
    over += fill_[i] >= 1.05f;
    over_active += fill_[i] >= 1.05f && lambda_[i] > 0.0f;
  }
  fmt::print(stderr, "adaptive t={:.4f}: {} samples, λ > 0: {}, under-filled at start: {}, over-full ≥ 1.05: {} ({} with λ > 0)\n",
             time_, m, active_.size(), under, over, over_active);
}

void AdaptiveController::CorrectionLimit::apply(sim::ParticleSet& p, std::size_t j, Vec3f dx) const {
  dx *= alpha;
  const std::uint8_t t = p.target[j];
  const float d2 = dx.squaredNorm(), m = max_dx[t < targets ? t : 0];
  if (d2 > m * m) dx *= m / std::sqrt(d2);
  p.predicted[j] += dx;
  if (kinematic) p.shift[j] += dx;
}

// Δx_j scattered from the few active samples (serially, in sample order: deterministic).
void AdaptiveController::scatter_correction(sim::ParticleSet& p, const CorrectionLimit& limit) {
  const std::size_t n = p.size();
  const Vec3f* xs = p.predicted.data();
  const std::uint8_t* tf = p.target.data();
  const float mp = ctx_.particle_mass, kg = -spiky_.kgrad;
  dx_.assign(n, Vec3f::Zero());
  touched_.assign(n, 0);
  const Vec3f* x = p.position.data();  // bonds were decided at the start of the sub-step
  for (Index i : active_) {
    const std::uint8_t t = samples_.target[i];
    const Vec3f xi = samples_.position[i];  // the bond was decided at the start
    const Vec3f xe(sample_xw_[i].x, sample_xw_[i].y, sample_xw_[i].z);  // the correction acts at the end (begin_step)
    const float coef = strength_[t] * samples_.phi[i] * lambda_[i] * mp / samples_.rho_c[i] * kg, hs2 = bond_radius2_[i];
    for (Index j : cf_.of(i)) {
      if (tf[j] != t || (xi - x[j]).squaredNorm() > hs2) continue;
      const Vec3f r = xe - xs[j];
      const float r2 = r.squaredNorm();
      if (r2 >= spiky_.h2 || r2 == 0.0f) continue;
      const float len = std::sqrt(r2), q = spiky_.h - len;
      dx_[j] += (coef * q * q / len) * r;
      touched_[j] = 1;
    }
  }
  parallel_for(static_cast<std::int64_t>(n), [&](std::int64_t jj) {
    const auto j = static_cast<std::size_t>(jj);
    if (touched_[j]) limit.apply(p, j, dx_[j]);
  });
}

// Δx_j gathered over each fluid particle's bonds, four at a time, with the per-sample factor φ̃ λ m_p/ρ_c kg
// precomputed (0 when full; also 0 at the padding, which is out of reach too).
void AdaptiveController::gather_correction(sim::ParticleSet& p, const CorrectionLimit& limit) {
  using namespace core::simd;
  const Vec3f* xs = p.predicted.data();
  const __m128 sh = broadcast(spiky_.h), sh2 = broadcast(spiky_.h2), zero = _mm_setzero_ps();
  parallel_for(static_cast<std::int64_t>(p.size()), [&](std::int64_t jj) {
    const auto j = static_cast<std::size_t>(jj);
    const Index b = bond_off_[j], e = bond_off_[j + 1];
    if (b == e) return;
    const Vec3f xj = xs[j];
    const __m128 px = broadcast(xj.x()), py = broadcast(xj.y()), pz = broadcast(xj.z());
    __m128 dx = zero, dy = zero, dz = zero;
    for (Index k = b; k < e; k += 4) {
      const P4 xc = gather_packed(sample_xw_.data(), bond_idx_.data() + k);
      const __m128 c4 = xc.w;
      if (_mm_movemask_ps(_mm_cmpgt_ps(c4, zero)) == 0) continue;
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
    if (d.squaredNorm() > 0.0f) limit.apply(p, j, d);
  });
}

// The control acts in the nominal N_it iterations only: the solver's extra iterations (while the density error is
// high) are there to make the fluid incompressible, and more control sweeps would make the inflow depend on them.
void AdaptiveController::correct_positions(const sim::StepView& view, sim::ParticleSet& p) {
  if (view.iteration == 0 && params_.bond_breaking && params_.gamma > 0.0f) adaptive_spring(p, view.dt);
  if (view.iteration < std::max(1, view.iterations)) control_correction(p, view.dt);
}

}  // namespace ff::control
