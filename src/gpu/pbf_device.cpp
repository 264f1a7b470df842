#include "gpu/pbf_device.h"

#include "gpu/shaders.h"
#include "sim/surface_tension.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <cstring>

namespace ff::gpu {

// The push-constant block of shaders/common.glsl, word for word.
struct PbfDevice::Constants {
  float grid_lo[4];    // xyz corner, w 1/cell
  std::int32_t grid_dims[4];  // xyz cells, w n
  float k0[4];         // h, h², Poly6 k, W(0)
  float k1[4];         // mass, ρ0, ε, cgrad
  float k2[4];         // Δx: kgrad, w_ratio, scorr_c, scorr_n; force and update: gravity xyz, Δt
  float wall_lo[4];    // xyz walls, w m/ρ0
  float wall_hi[4];
  float k3[4];         // force: XSPH η/Δt, m · Poly6 k
};
static_assert(sizeof(PbfDevice::Constants) == kPushConstantBytes, "shaders/common.glsl's push-constant block is 128 bytes");

namespace {

using Constants = PbfDevice::Constants;

Constants make_constants(const GridSpec& g, std::size_t n, const sim::PbfLambdaConsts* lk, const sim::PbfDeltaConsts* dk) {
  Constants c{};
  c.grid_lo[0] = g.lo.x(), c.grid_lo[1] = g.lo.y(), c.grid_lo[2] = g.lo.z(), c.grid_lo[3] = 1.0f / g.cell;
  for (int a = 0; a < 3; ++a) c.grid_dims[a] = g.dims[static_cast<std::size_t>(a)];
  c.grid_dims[3] = static_cast<std::int32_t>(n);
  if (lk) {
    c.k0[0] = lk->h, c.k0[1] = lk->h2, c.k0[2] = lk->poly6_k, c.k0[3] = lk->w0;
    c.k1[0] = lk->mass, c.k1[1] = lk->rho0, c.k1[2] = lk->epsilon, c.k1[3] = lk->cgrad;
  }
  if (dk) {
    c.k2[0] = dk->kgrad, c.k2[1] = dk->w_ratio, c.k2[2] = dk->scorr_c, c.k2[3] = static_cast<float>(dk->scorr_n);
    for (int a = 0; a < 3; ++a) c.wall_lo[a] = dk->lo[a], c.wall_hi[a] = dk->hi[a];
    c.wall_lo[3] = dk->m_rho0;
  }
  return c;
}

// The prediction and update passes read gravity and Δt where the Δx pass reads its constants: their own block.
Constants step_constants(Constants c, const sim::PbfForceConsts& fk) {
  for (int a = 0; a < 3; ++a) c.k2[a] = fk.gravity[a];
  c.k2[3] = fk.dt;
  c.k3[0] = fk.xsph, c.k3[1] = fk.mass_poly6_k;
  return c;
}

// The force pass also reads the drag's coefficients, in the walls' slots (it does not clamp to the walls).
Constants force_constants(const Constants& c, const sim::PbfForceConsts& fk) {
  Constants f = step_constants(c, fk);
  f.wall_lo[0] = fk.drag_L, f.wall_lo[1] = fk.drag_y, f.wall_lo[2] = fk.drag_re, f.wall_lo[3] = fk.drag_d2;
  f.wall_hi[0] = fk.drag_acc, f.wall_hi[1] = f.wall_hi[2] = f.wall_hi[3] = 0.0f;
  return f;
}

std::uint32_t groups(std::size_t items, std::uint32_t size) { return static_cast<std::uint32_t>((items + size - 1) / size); }

}  // namespace

Result<GridSpec> GridSpec::covering(const Vec3f& lo, const Vec3f& hi, float cell, std::size_t max_cells) {
  if (!(cell > 0.0f) || !std::isfinite(cell)) return param_error(fmt::format("GPU grid: cell edge {} is not positive", cell));
  if (!lo.allFinite() || !hi.allFinite() || (hi - lo).minCoeff() < 0.0f)
    return param_error("GPU grid: the box is empty or not finite");
  GridSpec g;
  g.lo = lo;
  g.cell = cell;
  std::size_t total = 1;
  for (int a = 0; a < 3; ++a) {
    const double cells = std::floor(static_cast<double>(hi[a] - lo[a]) / cell) + 1.0;
    if (cells > static_cast<double>(max_cells)) return param_error("GPU grid: too many cells");
    g.dims[static_cast<std::size_t>(a)] = static_cast<int>(cells);
    total *= static_cast<std::size_t>(cells);
    if (total > max_cells)
      return param_error(fmt::format("GPU grid: {:.3g} m cells over the box need more than {} cells", cell, max_cells));
  }
  return g;
}

Result<std::unique_ptr<PbfDevice>> PbfDevice::create(Context& ctx, std::size_t n, const GridSpec& grid) {
  if (n == 0) return param_error("GPU PBF: no particles");
  if (n > static_cast<std::size_t>(INT32_MAX)) return param_error("GPU PBF: more than 2^31 particles");
  // Every pass dispatches along x only: its groups (64 particles or 256 cells the smallest) must fit the device's limit.
  const double most = static_cast<double>(ctx.max_groups());
  if (static_cast<double>(n) > 64.0 * most || static_cast<double>(grid.cells()) > 256.0 * most)
    return param_error(fmt::format("GPU PBF: {} particles or {} grid cells are more than {} allows in one dispatch ({} "
                                   "workgroups)", n, grid.cells(), ctx.info().name, ctx.max_groups()));
  std::unique_ptr<PbfDevice> d(new PbfDevice());
  d->ctx_ = &ctx;
  d->n_ = n;
  d->grid_ = grid;
  const VkDeviceSize v4 = n * 16, u = n * 4, cells = grid.cells();
  FF_TRY(d->pos_, DeviceBuffer::create(ctx, v4));
  FF_TRY(d->next_, DeviceBuffer::create(ctx, v4));
  FF_TRY(d->cell_, DeviceBuffer::create(ctx, u));
  FF_TRY(d->count_, DeviceBuffer::create(ctx, cells * 4));
  FF_TRY(d->start_, DeviceBuffer::create(ctx, (cells + 1) * 4));
  FF_TRY(d->items_, DeviceBuffer::create(ctx, u));
  FF_TRY(d->density_, DeviceBuffer::create(ctx, u));
  FF_TRY(d->lambda_, DeviceBuffer::create(ctx, u));
  FF_TRY(d->x_, DeviceBuffer::create(ctx, v4));
  FF_TRY(d->vel_, DeviceBuffer::create(ctx, v4));
  FF_TRY(d->check_, DeviceBuffer::create(ctx, 8));
  FF_TRY(d->accel_, DeviceBuffer::create(ctx, v4));
  FF_TRY(d->shift_, DeviceBuffer::create(ctx, v4));
  FF_TRY(d->partial_, DeviceBuffer::create(ctx, groups(n, 256) * 4));
  FF_TRY(d->id_, DeviceBuffer::create(ctx, u));
  FF_TRY(d->st_class_, DeviceBuffer::create(ctx, u));
  FF_TRY(d->st_normal_, DeviceBuffer::create(ctx, v4));
  FF_TRY(d->st_curv_, DeviceBuffer::create(ctx, u));
  FF_TRY(d->points_, DeviceBuffer::create(ctx, 16 * 128));
  d->points_cap_ = 128;
  FF_TRY(d->state_, DeviceBuffer::create(ctx, kStateBytes));
  FF_TRY(d->count_k_, Kernel::create(ctx, "grid_count", shaders::grid_count(), {&d->pos_, &d->cell_, &d->count_}));
  FF_TRY(d->scan_k_, Kernel::create(ctx, "grid_scan", shaders::grid_scan(), {&d->count_, &d->start_}));
  FF_TRY(d->scatter_k_, Kernel::create(ctx, "grid_scatter", shaders::grid_scatter(),
                                       {&d->cell_, &d->start_, &d->count_, &d->items_}));
  FF_TRY(d->order_k_, Kernel::create(ctx, "grid_order", shaders::grid_order(), {&d->start_, &d->items_}));
  FF_TRY(d->lambda_k_, Kernel::create(ctx, "pbf_lambda", shaders::pbf_lambda(),
                                      {&d->pos_, &d->cell_, &d->start_, &d->items_, &d->density_, &d->lambda_, &d->state_}));
  FF_TRY(d->delta_k_, Kernel::create(ctx, "pbf_delta", shaders::pbf_delta(),
                                     {&d->pos_, &d->cell_, &d->start_, &d->items_, &d->lambda_, &d->next_, &d->state_}));
  FF_TRY(d->copy_k_, Kernel::create(ctx, "pbf_copy", shaders::pbf_copy(), {&d->next_, &d->pos_, &d->state_}));
  FF_TRY(d->error_k_, Kernel::create(ctx, "density_error", shaders::density_error(), {&d->density_, &d->partial_, &d->state_}));
  FF_TRY(d->decide_k_, Kernel::create(ctx, "density_decide", shaders::density_decide(), {&d->partial_, &d->state_}));
  FF_CHECK(d->make_surface_kernels());
  std::vector<std::uint32_t> ids(n);
  for (std::size_t i = 0; i < n; ++i) ids[i] = static_cast<std::uint32_t>(i);
  FF_CHECK(d->id_.upload(ids.data(), n * 4));
  FF_TRY(d->force_k_, Kernel::create(ctx, "pbf_force", shaders::pbf_force(),
                                     {&d->pos_, &d->cell_, &d->start_, &d->items_, &d->vel_, &d->density_, &d->accel_}));
  FF_TRY(d->predict_k_, Kernel::create(ctx, "pbf_predict", shaders::pbf_predict(), {&d->x_, &d->vel_, &d->accel_, &d->pos_}));
  FF_TRY(d->update_k_,
         Kernel::create(ctx, "pbf_update", shaders::pbf_update(), {&d->pos_, &d->x_, &d->vel_, &d->shift_}));
  FF_TRY(d->check_k_, Kernel::create(ctx, "frame_check", shaders::frame_check(), {&d->x_, &d->vel_, &d->check_}));
  if (ctx.timestamp_valid_bits() > 0 && ctx.timestamp_period_ns() > 0.0f) {
    VkQueryPoolCreateInfo qi{VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO};
    qi.queryType = VK_QUERY_TYPE_TIMESTAMP;
    qi.queryCount = 4 + 3 * kMaxTimedIterations;
    if (vkCreateQueryPool(ctx.device(), &qi, nullptr, &d->timestamps_) != VK_SUCCESS) d->timestamps_ = VK_NULL_HANDLE;
  }
  return d;
}

PbfDevice::~PbfDevice() {
  if (timestamps_) vkDestroyQueryPool(ctx_->device(), timestamps_, nullptr);
}

std::size_t PbfDevice::bytes() const {
  return pos_.bytes() + next_.bytes() + cell_.bytes() + count_.bytes() + start_.bytes() + items_.bytes() +
         density_.bytes() + lambda_.bytes() + x_.bytes() + vel_.bytes() + accel_.bytes() + omega_.bytes();
}

Status PbfDevice::set_predicted(std::span<const Vec3f> x) {
  if (x.size() != n_) return param_error(fmt::format("GPU PBF: {} positions for {} particles", x.size(), n_));
  std::vector<float> packed(4 * n_, 0.0f);
  for (std::size_t i = 0; i < n_; ++i) std::memcpy(&packed[4 * i], x[i].data(), 3 * sizeof(float));
  return pos_.upload(packed.data(), packed.size() * sizeof(float));
}

Status PbfDevice::get_predicted(std::vector<Vec3f>& x) const {
  std::vector<float> packed(4 * n_);
  FF_CHECK(pos_.download(packed.data(), packed.size() * sizeof(float)));
  x.resize(n_);
  for (std::size_t i = 0; i < n_; ++i) x[i] = Vec3f(packed[4 * i], packed[4 * i + 1], packed[4 * i + 2]);
  return {};
}

Status PbfDevice::get_density(std::vector<float>& rho) const {
  rho.resize(n_);
  return density_.download(rho.data(), n_ * sizeof(float));
}

Status PbfDevice::get_lambda(std::vector<float>& lambda) const {
  lambda.resize(n_);
  return lambda_.download(lambda.data(), n_ * sizeof(float));
}

Status PbfDevice::get_grid(std::vector<std::uint32_t>& start, std::vector<std::uint32_t>& items) const {
  start.resize(grid_.cells() + 1);
  items.resize(n_);
  FF_CHECK(start_.download(start.data(), start.size() * 4));
  return items_.download(items.data(), items.size() * 4);
}

// Counting sort of the particles into the grid's cells: count, scan, scatter, order each cell's run by index.
void PbfDevice::record_grid(VkCommandBuffer cb, const void* constants) const {
  vkCmdFillBuffer(cb, count_.handle(), 0, VK_WHOLE_SIZE, 0);
  compute_barrier(cb);
  count_k_.dispatch(cb, constants, groups(n_, 256));
  compute_barrier(cb);
  scan_k_.dispatch(cb, constants, 1);
  compute_barrier(cb);
  vkCmdFillBuffer(cb, count_.handle(), 0, VK_WHOLE_SIZE, 0);  // the counts become the scatter's cursors
  compute_barrier(cb);
  scatter_k_.dispatch(cb, constants, groups(n_, 256));
  compute_barrier(cb);
  order_k_.dispatch(cb, constants, groups(grid_.cells(), 256));
  compute_barrier(cb);
}

template <class Stamp>
void PbfDevice::record_sweeps(VkCommandBuffer cb, const void* constants, const Sweeps& sweeps, Stamp&& stamp,
                              float dt) const {
  // The passes of a sweep past the first `iterations` return at once when the sweeps are done (a flag on the device:
  // the host never waits in a sub-step).
  for (int it = 0; it < std::max(sweeps.max_iterations, sweeps.iterations); ++it) {
    if (controller_ && dt > 0.0f && it < sweeps.iterations) controller_->record_correction(cb, it, dt);
    lambda_k_.dispatch(cb, constants, groups(n_, 128));
    compute_barrier(cb);
    stamp(cb);
    delta_k_.dispatch(cb, constants, groups(n_, 128));
    compute_barrier(cb);
    stamp(cb);
    copy_k_.dispatch(cb, constants, groups(n_, 256));  // Jacobi: x* ← next
    error_k_.dispatch(cb, constants, groups(n_, 256));  // reads the λ pass's densities, not x*
    compute_barrier(cb);
    decide_k_.dispatch(cb, constants, 1);
    compute_barrier(cb);
    stamp(cb);
  }
}

void PbfDevice::reset_sweeps(VkCommandBuffer cb, bool frame) const {
  // done, sweeps, mean, max bits = 0 each sub-step; the frame's total too at its start.
  vkCmdFillBuffer(cb, state_.handle(), 0, 16, 0);
  if (frame) vkCmdFillBuffer(cb, state_.handle(), 16, 8, 0);
  compute_barrier(cb);
}

// Timestamps of a timed submission: [0] start, [1] after the grid, then (substep only) [2] after the force pass and
// its copy, then three per sweep, then (substep only) one after the update.
Status PbfDevice::read_times(int iterations, bool with_force, PassTimes& times) const {
  const std::uint32_t sweeps = static_cast<std::uint32_t>(iterations);
  const std::uint32_t queries = 2 + (with_force ? 2u : 0u) + 3 * sweeps;
  std::vector<std::uint64_t> t(queries);
  if (const VkResult r = vkGetQueryPoolResults(ctx_->device(), timestamps_, 0, queries, t.size() * 8, t.data(), 8,
                                               VK_QUERY_RESULT_64_BIT | VK_QUERY_RESULT_WAIT_BIT);
      r != VK_SUCCESS)
    return io_error(fmt::format("Vulkan: reading the timestamps failed ({})", vk_result_name(r)));
  const double ms = ctx_->timestamp_period_ns() * 1e-6;
  const std::uint32_t bits = ctx_->timestamp_valid_bits();
  const std::uint64_t mask = bits >= 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << bits) - 1;  // counters may wrap
  const auto span = [&](std::uint32_t a, std::uint32_t b) { return static_cast<double>((t[b] - t[a]) & mask) * ms; };
  times.grid = span(0, 1);
  std::uint32_t q = 1;
  if (with_force) times.force = span(1, 2), q = 2;
  for (std::uint32_t it = 0; it < sweeps; ++it, q += 3) {
    times.lambda += span(q, q + 1);
    times.delta += span(q + 1, q + 2);
    times.copy += span(q + 2, q + 3);
  }
  if (with_force) times.update = span(q, q + 1);
  return {};
}

namespace {

// Timestamps after the passes of a timed submission (the barriers before each order the passes): one query each,
// in order; nothing when not timed.
struct Stamps {
  VkQueryPool pool = VK_NULL_HANDLE;
  bool on = false;
  std::uint32_t next = 0;
  void operator()(VkCommandBuffer cb) {
    if (on) vkCmdWriteTimestamp(cb, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT, pool, next++);
  }
  void reset(VkCommandBuffer cb, std::uint32_t queries) const {
    if (on) vkCmdResetQueryPool(cb, pool, 0, queries);
  }
};

}  // namespace

// What every way of stepping on the device checks and prepares first: the cells cover the support, the sub-step is
// positive, the surface tension's points are on the device; then the sweeps' constants (c), the force pass's (cf) and
// the prediction's and update's (cs). The controller prepares its sub-steps itself (prepare_frame).
Status PbfDevice::prepare_substeps(const sim::PbfLambdaConsts& lk, const sim::PbfDeltaConsts& dk,
                                   const sim::PbfForceConsts& fk, const Sweeps& sweeps, Constants& c, Constants& cf,
                                   Constants& cs) {
  if (lk.h > grid_.cell) return param_error(fmt::format("GPU PBF: h = {} is larger than the grid's cells ({})", lk.h, grid_.cell));
  if (!(fk.dt > 0.0f)) return param_error(fmt::format("GPU PBF: sub-step {} s is not positive", fk.dt));
  if (fk.st_sigma > 0.0f) FF_CHECK(prepare_points(sim::surface_tension_samples(fk.st_samples_per_second, fk.dt)));
  if (fk.vorticity > 0.0f && omega_.bytes() == 0) FF_CHECK(make_vorticity_kernels());
  lk_ = lk;
  c = make_constants(grid_, n_, &lk, &dk);
  c.k3[2] = static_cast<float>(sweeps.iterations), c.k3[3] = sweeps.target;
  cf = force_constants(c, fk);
  cs = step_constants(c, fk);
  return {};
}

Status PbfDevice::solve(const sim::PbfLambdaConsts& lk, const sim::PbfDeltaConsts& dk, int iterations, PassTimes* times) {
  if (lk.h > grid_.cell) return param_error(fmt::format("GPU PBF: h = {} is larger than the grid's cells ({})", lk.h, grid_.cell));
  Constants c = make_constants(grid_, n_, &lk, &dk);
  c.k3[2] = static_cast<float>(iterations), c.k3[3] = -1.0f;  // exactly `iterations` sweeps
  if (times) *times = {};
  const bool timed = times && timestamps_ && iterations <= kMaxTimedIterations;
  Stamps stamp{timestamps_, timed};
  FF_CHECK(ctx_->submit_and_wait([&](VkCommandBuffer cb) {
    stamp.reset(cb, 4 + 3 * kMaxTimedIterations);
    reset_sweeps(cb, true);
    stamp(cb);
    record_grid(cb, &c);
    stamp(cb);
    record_sweeps(cb, &c, Sweeps{iterations, iterations, -1.0f}, stamp, 0.0f);  // a bare solve: no controller
  }));
  return timed ? read_times(iterations, false, *times) : Status{};
}

Status PbfDevice::set_state(std::span<const Vec3f> x, std::span<const Vec3f> v) {
  if (x.size() != n_ || v.size() != n_)
    return param_error(fmt::format("GPU PBF: {} positions and {} velocities for {} particles", x.size(), v.size(), n_));
  std::vector<float> packed(4 * n_, 0.0f);
  for (std::size_t i = 0; i < n_; ++i) std::memcpy(&packed[4 * i], x[i].data(), 3 * sizeof(float));
  FF_CHECK(x_.upload(packed.data(), packed.size() * sizeof(float)));
  for (std::size_t i = 0; i < n_; ++i) std::memcpy(&packed[4 * i], v[i].data(), 3 * sizeof(float));
  return vel_.upload(packed.data(), packed.size() * sizeof(float));
}

Status PbfDevice::get_state(std::vector<Vec3f>& x, std::vector<Vec3f>& v) const {
  std::vector<float> px(4 * n_), pv(4 * n_);
  FF_CHECK(x_.download(px.data(), px.size() * sizeof(float)));
  FF_CHECK(vel_.download(pv.data(), pv.size() * sizeof(float)));
  x.resize(n_);
  v.resize(n_);
  for (std::size_t i = 0; i < n_; ++i) {
    x[i] = Vec3f(px[4 * i], px[4 * i + 1], px[4 * i + 2]);
    v[i] = Vec3f(pv[4 * i], pv[4 * i + 1], pv[4 * i + 2]);
  }
  return {};
}

template <class Stamp>
void PbfDevice::record_substep(VkCommandBuffer cb, const Constants& c, const Constants& cf, const Constants& cs,
                               const sim::PbfForceConsts& fk, const Sweeps& sweeps, int substep, Stamp&& stamp) const {
  reset_sweeps(cb, false);
  stamp(cb);
  // The grid on x, as the CPU's lists: x goes to the x* buffer, which the grid and the density pass read.
  const VkBufferCopy all{0, 0, n_ * 16};
  vkCmdCopyBuffer(cb, x_.handle(), pos_.handle(), 1, &all);
  vkCmdFillBuffer(cb, shift_.handle(), 0, VK_WHOLE_SIZE, 0);  // as the CPU's prediction zeroes ParticleSet::shift
  compute_barrier(cb);
  record_grid(cb, &c);
  stamp(cb);
  const float dt = cs.k2[3];
  if (controller_) controller_->record_begin(cb, dt, substep);
  lambda_k_.dispatch(cb, &c, groups(n_, 128));  // ρ(x) for XSPH (its λ is not used)
  compute_barrier(cb);
  force_k_.dispatch(cb, &cf, groups(n_, 128));
  compute_barrier(cb);
  if (fk.st_sigma > 0.0f) record_surface_tension(cb, fk, lk_);
  if (controller_) controller_->record_accelerations(cb, dt);
  predict_k_.dispatch(cb, &cs, groups(n_, 256));  // x* (the x buffer was copied into it for the grid)
  compute_barrier(cb);
  stamp(cb);
  record_sweeps(cb, &c, sweeps, stamp, dt);
  if (fk.vorticity > 0.0f) {  // its passes need x of the sub-step's start, which the update overwrites
    const VkBufferCopy all_x{0, 0, n_ * 16};
    vkCmdCopyBuffer(cb, x_.handle(), next_.handle(), 1, &all_x);  // next_ is free once the sweeps are done
    compute_barrier(cb);
  }
  update_k_.dispatch(cb, &cs, groups(n_, 256));
  compute_barrier(cb);
  if (fk.vorticity > 0.0f) record_vorticity(cb, c, fk);
  stamp(cb);
}

// The buffer and both kernels, kept only once all three exist: a failure leaves omega_ empty, so the next sub-step
// that asks for vorticity tries again instead of dispatching half-made kernels.
Status PbfDevice::make_vorticity_kernels() {
  Context& ctx = *ctx_;
  FF_TRY(DeviceBuffer omega, DeviceBuffer::create(ctx, n_ * 16));
  FF_TRY(Kernel w, Kernel::create(ctx, "vort_omega", shaders::vort_omega(),
                                  {&next_, &cell_, &start_, &items_, &vel_, &density_, &omega}));
  FF_TRY(Kernel apply, Kernel::create(ctx, "vort_apply", shaders::vort_apply(),
                                      {&next_, &cell_, &start_, &items_, &vel_, &density_, &omega}));
  omega_ = std::move(omega);  // the kernels' descriptor sets hold the buffer's handle, which the move keeps
  vort_omega_k_ = std::move(w);
  vort_apply_k_ = std::move(apply);
  return {};
}

// After the update: ω from the new velocities at x (in next_), then v += Δt ε_v (N × ω), as the CPU's
// PbfSolver::vorticity_confinement. c is the sweeps' block (h, m, Spiky kgrad); k2.y carries Δt ε_v.
void PbfDevice::record_vorticity(VkCommandBuffer cb, const Constants& c, const sim::PbfForceConsts& fk) const {
  Constants cv = c;
  cv.k2[1] = fk.dt * fk.vorticity;
  vort_omega_k_.dispatch(cb, &cv, groups(n_, 128));
  compute_barrier(cb);
  vort_apply_k_.dispatch(cb, &cv, groups(n_, 128));
  compute_barrier(cb);
}

Status PbfDevice::substep(const sim::PbfLambdaConsts& lk, const sim::PbfDeltaConsts& dk, const sim::PbfForceConsts& fk,
                          const Sweeps& sweeps, PassTimes* times) {
  const int iterations = std::max(sweeps.iterations, sweeps.max_iterations);
  Constants c, cf, cs;
  FF_CHECK(prepare_substeps(lk, dk, fk, sweeps, c, cf, cs));
  if (controller_)  // a lone sub-step: from time 0
    if (Result<int> prepared = controller_->prepare_frame(0.0, fk.dt, 0, 1); !prepared) return prepared.error();
  if (times) *times = {};
  const bool timed = times && timestamps_ && iterations <= kMaxTimedIterations;
  Stamps stamp{timestamps_, timed};
  FF_CHECK(ctx_->submit_and_wait([&](VkCommandBuffer cb) {
    stamp.reset(cb, 4 + 3 * kMaxTimedIterations);
    reset_sweeps(cb, true);
    record_substep(cb, c, cf, cs, fk, sweeps, 0, stamp);
  }));
  return timed ? read_times(iterations, true, *times) : Status{};
}

Result<PbfDevice::PointGrid> PbfDevice::sort_into_grid(const DeviceBuffer& points, std::size_t count,
                                                      const GridSpec* other) const {
  if (count == 0) return param_error("GPU grid: no points");
  const GridSpec& spec = other ? *other : grid_;
  Context& ctx = *ctx_;
  PointGrid g;
  g.points = count;
  g.spec = spec;
  FF_TRY(g.cell, DeviceBuffer::create(ctx, count * 4));
  FF_TRY(g.count, DeviceBuffer::create(ctx, spec.cells() * 4));
  FF_TRY(g.start, DeviceBuffer::create(ctx, (spec.cells() + 1) * 4));
  FF_TRY(g.items, DeviceBuffer::create(ctx, count * 4));
  FF_TRY(g.count_k, Kernel::create(ctx, "grid_count", shaders::grid_count(), {&points, &g.cell, &g.count}));
  FF_TRY(g.scan_k, Kernel::create(ctx, "grid_scan", shaders::grid_scan(), {&g.count, &g.start}));
  FF_TRY(g.scatter_k, Kernel::create(ctx, "grid_scatter", shaders::grid_scatter(), {&g.cell, &g.start, &g.count, &g.items}));
  FF_TRY(g.order_k, Kernel::create(ctx, "grid_order", shaders::grid_order(), {&g.start, &g.items}));
  FF_CHECK(ctx.submit_and_wait([&](VkCommandBuffer cb) { record_point_grid(cb, g); }));
  return g;
}

void PbfDevice::record_point_grid(VkCommandBuffer cb, const PointGrid& g) const {
  const Constants c = make_constants(g.spec, g.points, nullptr, nullptr);
  vkCmdFillBuffer(cb, g.count.handle(), 0, VK_WHOLE_SIZE, 0);
  compute_barrier(cb);
  g.count_k.dispatch(cb, &c, groups(g.points, 256));
  compute_barrier(cb);
  g.scan_k.dispatch(cb, &c, 1);
  compute_barrier(cb);
  vkCmdFillBuffer(cb, g.count.handle(), 0, VK_WHOLE_SIZE, 0);
  compute_barrier(cb);
  g.scatter_k.dispatch(cb, &c, groups(g.points, 256));
  compute_barrier(cb);
  g.order_k.dispatch(cb, &c, groups(g.spec.cells(), 256));
  compute_barrier(cb);
}

Status PbfDevice::make_surface_kernels() {
  Context& ctx = *ctx_;
  FF_TRY(st_estimate_k_, Kernel::create(ctx, "st_estimate", shaders::st_estimate(),
                                        {&pos_, &cell_, &start_, &items_, &id_, &points_, &st_class_, &st_normal_, &st_curv_}));
  FF_TRY(st_smooth_k_, Kernel::create(ctx, "st_smooth", shaders::st_smooth(),
                                      {&pos_, &cell_, &start_, &items_, &st_class_, &st_normal_, &st_curv_, &accel_}));
  return {};
}

Status PbfDevice::set_ids(std::span<const Index> id) {
  if (id.size() != n_) return param_error(fmt::format("GPU PBF: {} ids for {} particles", id.size(), n_));
  const std::vector<std::uint32_t> ids(id.begin(), id.end());
  FF_CHECK(id_.upload(ids.data(), n_ * 4));
  ids_.assign(id.begin(), id.end());
  return {};
}

// The spherical Fibonacci set of `n` points (sim/surface_tension.cpp, prepare_points, in double as there), on the
// device; the kernels that read it are bound again when the buffer grows.
Status PbfDevice::prepare_points(int n) {
  if (n == points_n_) return {};
  const auto count = static_cast<std::size_t>(n);
  if (count > points_cap_) {
    // The larger buffer, then the kernels bound to it; the size is raised only once both exist.
    FF_TRY(DeviceBuffer bigger, DeviceBuffer::create(*ctx_, 16 * count));
    std::swap(points_, bigger);
    if (const Status s = make_surface_kernels(); !s.ok()) {
      std::swap(points_, bigger);
      FF_CHECK(make_surface_kernels());  // the old buffer's kernels again
      return s;
    }
    points_cap_ = count;
    points_n_ = 0;
  }
  std::vector<float> p(4 * count, 0.0f);
  const double golden = std::numbers::pi * (3.0 - std::sqrt(5.0));
  for (std::size_t k = 0; k < count; ++k) {
    const double z = 1.0 - (2.0 * double(k) + 1.0) / n, rho = std::sqrt(std::max(0.0, 1.0 - z * z)), phi = golden * double(k);
    p[4 * k] = static_cast<float>(rho * std::cos(phi));
    p[4 * k + 1] = static_cast<float>(rho * std::sin(phi));
    p[4 * k + 2] = static_cast<float>(z);
  }
  FF_CHECK(points_.upload(p.data(), p.size() * 4));
  points_n_ = n;
  return {};
}

namespace {

// The push-constant block of shaders/surface.glsl, padded to 128 bytes.
struct SurfaceConstants {
  float grid_lo[4];
  std::int32_t grid_dims[4];
  float s0[4];          // h, r2/r1, classifier k, d_c
  std::uint32_t s1[4];  // key low, key high, points
  float s2[4];          // τ, −σ/m, κ scale, κ shift
  float pad[12];
};
static_assert(sizeof(SurfaceConstants) == kPushConstantBytes, "shaders/surface.glsl's block, padded to 128 bytes");

}  // namespace

void PbfDevice::record_surface_tension(VkCommandBuffer cb, const sim::PbfForceConsts& fk, const sim::PbfLambdaConsts& lk) const {
  const sim::SurfaceTensionParams st;  // r2/r1, τ and the classifier: the CPU's defaults
  SurfaceConstants k{};
  k.grid_lo[0] = grid_.lo.x(), k.grid_lo[1] = grid_.lo.y(), k.grid_lo[2] = grid_.lo.z(), k.grid_lo[3] = 1.0f / grid_.cell;
  for (int a = 0; a < 3; ++a) k.grid_dims[a] = grid_.dims[static_cast<std::size_t>(a)];
  k.grid_dims[3] = static_cast<std::int32_t>(n_);
  k.s0[0] = lk.h, k.s0[1] = st.r2_ratio, k.s0[2] = st.class_k, k.s0[3] = st.class_d;
  k.s1[0] = static_cast<std::uint32_t>(fk.st_key), k.s1[1] = static_cast<std::uint32_t>(fk.st_key >> 32);
  k.s1[2] = static_cast<std::uint32_t>(points_n_);
  const double ratio = st.r2_ratio;
  k.s2[0] = st.tau, k.s2[1] = -fk.st_sigma / lk.mass;
  k.s2[2] = static_cast<float>(-2.0 / double(lk.h) / std::sqrt(1.0 - ratio * ratio));
  k.s2[3] = static_cast<float>(std::asin(ratio));
  st_estimate_k_.dispatch(cb, &k, groups(n_, 64));
  compute_barrier(cb);
  st_smooth_k_.dispatch(cb, &k, groups(n_, 128));
  compute_barrier(cb);
}

Result<PbfDevice::SurfaceResult> PbfDevice::surface_tension_only(const sim::PbfLambdaConsts& lk,
                                                                const sim::PbfForceConsts& fk) {
  if (!(fk.st_sigma > 0.0f)) return param_error("GPU surface tension: σ is 0");
  FF_CHECK(prepare_points(sim::surface_tension_samples(fk.st_samples_per_second, fk.dt)));
  const Constants c = make_constants(grid_, n_, &lk, nullptr);
  FF_CHECK(ctx_->submit_and_wait([&](VkCommandBuffer cb) {
    const VkBufferCopy all{0, 0, n_ * 16};
    vkCmdCopyBuffer(cb, x_.handle(), pos_.handle(), 1, &all);
    vkCmdFillBuffer(cb, accel_.handle(), 0, VK_WHOLE_SIZE, 0);
    compute_barrier(cb);
    record_grid(cb, &c);
    record_surface_tension(cb, fk, lk);
  }));
  SurfaceResult r;
  std::vector<std::uint32_t> cls(n_);
  std::vector<float> nrm(4 * n_), acc(4 * n_);
  r.curv.resize(n_);
  FF_CHECK(st_class_.download(cls.data(), n_ * 4));
  FF_CHECK(st_normal_.download(nrm.data(), n_ * 16));
  FF_CHECK(st_curv_.download(r.curv.data(), n_ * 4));
  FF_CHECK(accel_.download(acc.data(), n_ * 16));
  r.cls.assign(cls.begin(), cls.end());
  for (std::size_t i = 0; i < n_; ++i) {
    r.normal.emplace_back(nrm[4 * i], nrm[4 * i + 1], nrm[4 * i + 2]);
    r.accel.emplace_back(acc[4 * i], acc[4 * i + 1], acc[4 * i + 2]);
  }
  return r;
}

Result<PbfDevice::Check> PbfDevice::check() {
  const Constants c = make_constants(grid_, n_, nullptr, nullptr);
  FF_CHECK(ctx_->submit_and_wait([&](VkCommandBuffer cb) {
    vkCmdFillBuffer(cb, check_.handle(), 0, 4, 0);               // max |v|² bits: 0 is +0.0
    vkCmdFillBuffer(cb, check_.handle(), 4, 4, 0xFFFFFFFFu);     // no bad particle
    compute_barrier(cb);
    check_k_.dispatch(cb, &c, groups(n_, 256));
  }));
  std::uint32_t r[2];
  FF_CHECK(check_.download(r, sizeof r));
  float v2;
  std::memcpy(&v2, &r[0], sizeof v2);
  return Check{std::sqrt(static_cast<double>(v2)), r[1] == 0xFFFFFFFFu ? n_ : static_cast<std::size_t>(r[1])};
}

Result<DeviceFrame> PbfDevice::advance(const sim::PbfSolver& solver, double time, double frame_dt) {
  const auto blown = [&](std::size_t i, int step) {
    return numerical_error(fmt::format("simulation blew up in sub-step {} on the GPU: particle {} has a non-finite "
                                       "position or velocity", step, i < ids_.size() ? ids_[i] : Index(i)));
  };
  FF_TRY(const Check before, check());
  if (before.first_bad < n_) return blown(before.first_bad, 0);
  const sim::SubstepPlan plan = sim::plan_substeps(solver.params(), before.max_speed, frame_dt);
  const sim::PbfLambdaConsts lk = solver.lambda_consts();
  const sim::PbfDeltaConsts dk = solver.delta_consts();
  sim::PbfForceConsts fk = solver.force_consts(plan.dt);
  const sim::SolverParams& sp = solver.params();
  const Sweeps sweeps{sp.iterations, sp.max_iterations, sp.max_density_error};
  Constants c, cf, cs;
  FF_CHECK(prepare_substeps(lk, dk, fk, sweeps, c, cf, cs));
  // Every sub-step in one submission: the device runs the frame without waiting for the host. Only a controller whose
  // samples change inside the frame (a morph's swap) ends one there, and the next starts from the new samples.
  for (int from = 0, upto = plan.steps; from < plan.steps; from = upto) {
    if (controller_) {
      FF_TRY(upto, controller_->prepare_frame(time, plan.dt, from, plan.steps));
    }
    FF_CHECK(ctx_->submit_and_wait([&](VkCommandBuffer cb) {
      if (from == 0) reset_sweeps(cb, true);
      for (int s = from; s < upto; ++s) {
        fk.st_key = sim::surface_tension_step_key(time + s * double(plan.dt));  // the CPU's key for this sub-step
        record_substep(cb, c, cf, cs, fk, sweeps, s, [](VkCommandBuffer) {});
      }
    }));
  }
  FF_TRY(const Check after, check());
  if (after.first_bad < n_) return blown(after.first_bad, plan.steps);
  struct {
    std::uint32_t done, sweeps;
    float mean;
    std::uint32_t max_bits, total;
    float last_max;
  } state;
  static_assert(sizeof state == kStateBytes);
  FF_CHECK(state_.download(&state, sizeof state));
  return DeviceFrame{plan.steps, plan.dt, plan.capped, before.max_speed, after.max_speed, static_cast<long>(state.total),
                     state.mean, state.last_max};
}

Status PbfDevice::lambda_only(const sim::PbfLambdaConsts& lk) {
  const Constants c = make_constants(grid_, n_, &lk, nullptr);
  return ctx_->submit_and_wait([&](VkCommandBuffer cb) { lambda_k_.dispatch(cb, &c, groups(n_, 128)); });
}

}  // namespace ff::gpu
