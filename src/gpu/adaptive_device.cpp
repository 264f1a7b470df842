#include "gpu/adaptive_device.h"

#include "control/nearest_seed_field.h"
#include "core/kernels.h"
#include "gpu/shaders.h"
#include "sampling/weights.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstring>

namespace ff::gpu {

// The push-constant block of shaders/control.glsl, word for word (padded to the 128 bytes every kernel pushes).
struct AdaptiveDevice::Constants {
  float grid_lo[4];
  std::int32_t grid_dims[4];
  float c0[4];  // H_c, H_c², Poly6 k at H_c, Spiky kgrad at H_c
  float c1[4];  // m_p, ε_c, α, the largest |Δx| per iteration
  float c2[4];  // γ (scaled to Δt), |n| threshold (< 0: no boundary correction), speed limit, Δt
  std::int32_t c3[4];  // samples, reach, bond radius rule, flags (several targets 1, kinematic 2)
  float field_lo[4];           // the seed field: corner, 1 / cell
  std::int32_t field_dims[4];  // cells per axis, targets
};
static_assert(sizeof(AdaptiveDevice::Constants) == kPushConstantBytes, "shaders/control.glsl's block, padded to 128 bytes");

namespace {

std::uint32_t groups(std::size_t items, std::uint32_t size) { return static_cast<std::uint32_t>((items + size - 1) / size); }

// SoA floats as vec4s (w = 0) for the device.
std::vector<float> packed(std::span<const Vec3f> v) {
  std::vector<float> out(4 * v.size(), 0.0f);
  for (std::size_t i = 0; i < v.size(); ++i) std::memcpy(&out[4 * i], v[i].data(), 3 * sizeof(float));
  return out;
}

}  // namespace

Result<std::unique_ptr<AdaptiveDevice>> AdaptiveDevice::create(PbfDevice& fluid, std::vector<control::ControlTarget> targets,
                                                              const control::ControlContext& ctx,
                                                              const control::AdaptiveParams& params) {
  FF_CHECK(params.validate());
  std::unique_ptr<AdaptiveDevice> a(new AdaptiveDevice());
  a->timed_ = std::any_of(targets.begin(), targets.end(),
                          [](const control::ControlTarget& t) { return t.start > 0.0 || !t.strength.keys.empty(); });
  a->morphs_ = std::any_of(targets.begin(), targets.end(),
                           [](const control::ControlTarget& t) { return !t.swaps.empty(); });
  control::ControlSamples& samples = a->samples_;
  FF_CHECK(samples.init(std::move(targets), "adaptive (GPU)",
                        {.cell_order = false, .weights = params.weights, .normals = true, .velocities = true}));
  if (samples.size() == 0) return input_error("adaptive (GPU): the targets have no control samples");
  a->fluid_ = &fluid;
  a->params_ = params;
  a->ctx_ = ctx;
  a->hc_ = samples.hc;
  a->multi_ = samples.targets() > 1;
  // ε_c as the CPU controller takes it (AdaptiveController::create): epsilon · S_0 of a full neighbourhood at H_c.
  const float d = ctx.spacing();
  const double rho_ref = sampling::lattice_density(d, a->hc_, ctx.rest_density);
  a->eps_c_ = static_cast<float>(params.epsilon * control::full_gradient_sum(d, a->hc_, ctx.particle_mass, rho_ref));

  FF_CHECK(a->make_buffers());
  FF_CHECK(a->make_kernels());
  return a;
}

// The passes, bound to the fluid's buffers and the samples' current ones (again after a morph's swap).
Status AdaptiveDevice::make_kernels() {
  Context& c = fluid_->context();
  const PbfDevice& fluid = *fluid_;
  const DeviceBuffer &fx = fluid.x_buffer(), &fpos = fluid.predicted_buffer(), &fcell = fluid.cell_buffer(),
                     &fstart = fluid.start_buffer(), &fitems = fluid.items_buffer();
  const PbfDevice::PointGrid& sg = s_grid_;
  FF_TRY(fill_k_, Kernel::create(c, "ctl_fill", shaders::ctl_fill(),
                                 {&s_pos_, &sg.cell, &s_rho_c_, &s_target_, &fx, &fstart, &fitems, &f_target_, &s_fill_,
                                  &s_bond_r2_, &t_strength_}));
  FF_TRY(bonds_k_, Kernel::create(c, "ctl_bonds", shaders::ctl_bonds(),
                                  {&fx, &fcell, &f_target_, &s_pos_, &sg.start, &sg.items, &s_target_, &s_bond_r2_,
                                   &nearest_}));
  FF_TRY(accel_k_, Kernel::create(c, "ctl_accel", shaders::ctl_accel(),
                                  {&nearest_, &s_normal_, &fluid.velocity_buffer(), &fluid.acceleration_buffer(),
                                   &f_target_, &s_vel_, &t_moving_, &t_strength_, &t_speed_}));
  FF_TRY(spring_k_, Kernel::create(c, "ctl_spring", shaders::ctl_spring(),
                                   {&fx, &fcell, &f_target_, &nearest_, &s_pos_, &sg.start, &sg.items, &s_target_,
                                    &s_bond_r2_, &s_fill_, &fpos, &s_vel_, &t_strength_, &fluid.shift_buffer()}));
  FF_TRY(lambda_k_, Kernel::create(c, "ctl_lambda", shaders::ctl_lambda(),
                                   {&s_pos_, &sg.cell, &s_rho_c_, &s_target_, &s_phi_, &fx, &fpos, &fstart, &fitems,
                                    &f_target_, &s_coef_, &s_vel_, &t_strength_}));
  FF_TRY(correct_k_, Kernel::create(c, "ctl_correct", shaders::ctl_correct(),
                                    {&fx, &fcell, &f_target_, &nearest_, &s_pos_, &sg.start, &sg.items, &s_target_,
                                     &s_bond_r2_, &s_coef_, &fpos, &s_vel_, &t_speed_, &fluid.shift_buffer()}));
  if (params_.gather) FF_CHECK(make_seed_field(samples_.targets()));
  return {};
}

// The fluid's per-particle buffers (its targets: 0 until set_fluid_targets) and the per-target ones, then the samples'.
Status AdaptiveDevice::make_buffers() {
  Context& c = fluid_->context();
  const std::size_t n = fluid_->size();
  FF_TRY(f_target_, DeviceBuffer::create(c, n * 4));
  FF_TRY(nearest_, DeviceBuffer::create(c, n * 4));
  const std::vector<std::uint32_t> zero(n, 0);
  FF_CHECK(f_target_.upload(zero.data(), n * 4));
  FF_TRY(t_moving_, DeviceBuffer::create(c, samples_.targets() * 4));
  FF_TRY(t_strength_, DeviceBuffer::create(c, samples_.targets() * 4));
  const std::vector<float> full(samples_.targets(), 1.0f);  // a timed scene's are copied in every sub-step
  FF_CHECK(t_strength_.upload(full.data(), full.size() * 4));
  return make_sample_buffers();
}

// The samples' buffers, filled from samples_' current sets, and the samples sorted into the fluid grid's cells.
Status AdaptiveDevice::make_sample_buffers() {
  Context& c = fluid_->context();
  m_ = samples_.size();
  g_ref_ = samples_.g_ref;
  original_ = samples_.original;
  const std::size_t m = m_;
  FF_TRY(s_pos_, DeviceBuffer::create(c, m * 16));
  FF_TRY(s_normal_, DeviceBuffer::create(c, m * 16));
  FF_TRY(s_rho_c_, DeviceBuffer::create(c, m * 4));
  FF_TRY(s_phi_, DeviceBuffer::create(c, m * 4));
  FF_TRY(s_target_, DeviceBuffer::create(c, m * 4));
  FF_TRY(s_fill_, DeviceBuffer::create(c, m * 4));
  FF_TRY(s_bond_r2_, DeviceBuffer::create(c, m * 4));
  FF_TRY(s_coef_, DeviceBuffer::create(c, m * 4));
  FF_TRY(s_vel_, DeviceBuffer::create(c, m * 16));
  // The speeds' factors as the CPU controller's (AdaptiveController::speed_scale_, max_dx_).
  const std::vector<float> scale = control::speed_scales(samples_.target, samples_.targets(), params_.speed_reference);
  std::vector<float> speed(2 * scale.size());
  for (std::size_t t = 0; t < scale.size(); ++t)
    speed[2 * t] = scale[t], speed[2 * t + 1] = std::min(1.0f, params_.clamp * scale[t]) / params_.clamp;
  FF_TRY(t_speed_, DeviceBuffer::create(c, speed.size() * 4));
  FF_CHECK(t_speed_.upload(speed.data(), speed.size() * 4));
  const std::vector<float> still(4 * m, 0.0f);
  FF_CHECK(s_vel_.upload(still.data(), still.size() * 4));
  const std::vector<float> pos = packed(samples_.position), nrm = packed(samples_.normal);
  const std::vector<std::uint32_t> target(samples_.target.begin(), samples_.target.end());
  FF_CHECK(s_pos_.upload(pos.data(), pos.size() * 4));
  FF_CHECK(s_normal_.upload(nrm.data(), nrm.size() * 4));
  FF_CHECK(s_rho_c_.upload(samples_.rho_c.data(), m * 4));
  FF_CHECK(s_phi_.upload(samples_.phi.data(), m * 4));
  FF_CHECK(s_target_.upload(target.data(), m * 4));
  FF_CHECK(upload_moving());
  FF_TRY(s_grid_, fluid_->sort_into_grid(s_pos_, m));
  return {};
}

// Per target, 1 when it moves (keyframes, a skin, a live pose): ctl_accel's follow applies to its fluid only.
Status AdaptiveDevice::upload_moving() {
  std::vector<std::uint32_t> moving(samples_.targets());
  for (std::size_t t = 0; t < moving.size(); ++t) moving[t] = samples_.moving(static_cast<std::uint8_t>(t)) ? 1u : 0u;
  return t_moving_.upload(moving.data(), moving.size() * 4);
}

// The seed field over the domain at the CPU field's cells, the samples sorted into them, and the flood's jumps.
Status AdaptiveDevice::make_seed_field(std::size_t targets) {
  control::NearestSeedField cpu;
  cpu.reset(ctx_.domain.min, ctx_.domain.max, hc_);
  field_.lo = cpu.lo();
  field_.cell = cpu.cell();
  for (int a = 0; a < 3; ++a) field_.dims[static_cast<std::size_t>(a)] = cpu.dims()[a];
  targets_ = targets;
  jumps_.clear();
  const int largest = std::max({field_.dims[0], field_.dims[1], field_.dims[2]});
  int jump = 1;
  while (jump * 2 < largest) jump *= 2;
  for (; jump >= 1; jump /= 2) jumps_.push_back(jump);
  jumps_.push_back(1);  // one more pass of 1 settles most of the cells the halving leaves a cell off
  Context& c = fluid_->context();
  const std::size_t cells = field_.cells() * targets_;
  FF_TRY(seed_a_, DeviceBuffer::create(c, cells * 4));
  FF_TRY(seed_b_, DeviceBuffer::create(c, cells * 4));
  FF_TRY(s_field_, fluid_->sort_into_grid(s_pos_, m_, &field_));
  FF_TRY(seed_init_k_, Kernel::create(c, "ctl_seed_init", shaders::ctl_seed_init(),
                                      {&s_pos_, &s_target_, &s_fill_, &s_field_.start, &s_field_.items, &seed_a_,
                                       &t_strength_}));
  FF_TRY(flood_ab_k_, Kernel::create(c, "ctl_seed_flood", shaders::ctl_seed_flood(), {&s_pos_, &seed_a_, &seed_b_}));
  FF_TRY(flood_ba_k_, Kernel::create(c, "ctl_seed_flood", shaders::ctl_seed_flood(), {&s_pos_, &seed_b_, &seed_a_}));
  FF_TRY(gather_k_, Kernel::create(c, "ctl_gather", shaders::ctl_gather(),
                                   {&fluid_->x_buffer(), &f_target_, &nearest_, &s_pos_, &seed_a_, &fluid_->velocity_buffer(),
                                    &fluid_->acceleration_buffer(), &s_vel_, &t_strength_, &t_speed_}));
  return {};
}

Status AdaptiveDevice::set_target_pose(std::size_t t, const pose::Pose& pose) {
  if (t >= samples_.targets()) return {};
  samples_.set_target_pose(t, pose);  // from now on samples_.moving(): poses are uploaded every frame
  return upload_moving();
}

Status AdaptiveDevice::set_fluid_targets(std::span<const std::uint8_t> target) {
  if (target.size() != fluid_->size())
    return param_error(fmt::format("adaptive (GPU): {} targets for {} fluid particles", target.size(), fluid_->size()));
  const std::vector<std::uint32_t> t(target.begin(), target.end());
  return f_target_.upload(t.data(), t.size() * 4);
}

Status AdaptiveDevice::get_bound(std::vector<Index>& bound) const {
  std::vector<std::uint32_t> near(fluid_->size());
  FF_CHECK(nearest_.download(near.data(), near.size() * 4));
  bound.resize(near.size());
  for (std::size_t j = 0; j < near.size(); ++j) bound[j] = near[j] == 0xFFFFFFFFu ? kInvalidIndex : original_[near[j]];
  return {};
}

Status AdaptiveDevice::get_seeds(std::vector<Index>& seeds) const {
  if (!params_.gather) return param_error("adaptive (GPU): no seed field without the gather steering");
  std::vector<std::uint32_t> raw(field_.cells() * targets_);
  FF_CHECK(seed_a_.download(raw.data(), raw.size() * 4));
  seeds.resize(raw.size());
  for (std::size_t k = 0; k < raw.size(); ++k) seeds[k] = raw[k] == 0xFFFFFFFFu ? kInvalidIndex : original_[raw[k]];
  return {};
}

Status AdaptiveDevice::get_fill(std::vector<float>& fill) const {
  std::vector<float> f(m_);
  FF_CHECK(s_fill_.download(f.data(), m_ * 4));
  fill.assign(m_, 0.0f);
  for (std::size_t k = 0; k < m_; ++k) fill[original_[k]] = f[k];
  return {};
}

AdaptiveDevice::Constants AdaptiveDevice::constants(float dt) const {
  Constants k{};
  const GridSpec& g = fluid_->grid();
  k.grid_lo[0] = g.lo.x(), k.grid_lo[1] = g.lo.y(), k.grid_lo[2] = g.lo.z(), k.grid_lo[3] = 1.0f / g.cell;
  for (int a = 0; a < 3; ++a) k.grid_dims[a] = g.dims[static_cast<std::size_t>(a)];
  k.grid_dims[3] = static_cast<std::int32_t>(fluid_->size());
  const core::Poly6 poly6(hc_);
  const core::Spiky spiky(hc_);
  k.c0[0] = hc_, k.c0[1] = poly6.h2, k.c0[2] = poly6.k, k.c0[3] = spiky.kgrad;
  const float d = ctx_.spacing(), ramp = std::min(1.0f, dt / control::kReferenceDt);
  k.c1[0] = ctx_.particle_mass, k.c1[1] = eps_c_, k.c1[2] = params_.alpha, k.c1[3] = params_.clamp * d * ramp;
  k.c2[0] = params_.bond_breaking ? params_.gamma * ramp : 0.0f;
  k.c2[1] = params_.boundary_correction ? params_.normal_threshold * g_ref_ : -1.0f;
  k.c2[2] = params_.max_speed * d, k.c2[3] = dt;
  k.c3[0] = static_cast<std::int32_t>(m_);
  k.c3[1] = static_cast<std::int32_t>(std::ceil(hc_ / g.cell));
  k.c3[2] = !params_.bond_breaking ? 2 : params_.bond_radius == control::BondRadius::Paper ? 1 : 0;
  k.c3[3] = (multi_ ? 1 : 0) | (params_.kinematic ? 2 : 0);  // shaders/control.glsl's SEVERAL_TARGETS, KINEMATIC
  if (field_.cell > 0.0f) {
    k.field_lo[0] = field_.lo.x(), k.field_lo[1] = field_.lo.y(), k.field_lo[2] = field_.lo.z(), k.field_lo[3] = 1.0f / field_.cell;
    for (int a = 0; a < 3; ++a) k.field_dims[a] = field_.dims[static_cast<std::size_t>(a)];
    k.field_dims[3] = static_cast<std::int32_t>(targets_);
  }
  return k;
}

// The accelerations pass's own reading of c0.x: the follow share (shaders/ctl_accel.comp).
AdaptiveDevice::Constants AdaptiveDevice::accel_constants(float dt) const {
  Constants k = constants(dt);
  const bool follow = samples_.moving() && params_.follow > 0.0f;
  k.c0[0] = follow ? std::min(1.0f, params_.follow * dt / control::kReferenceDt) : 0.0f;
  return k;
}

// The frame's strengths of a timed scene, every sub-step's, into step_strength_ (record_begin copies one in).
Status AdaptiveDevice::prepare_strengths(double time, float dt, std::size_t steps) {
  const std::size_t targets = samples_.targets();
  if (steps > strength_steps_) {
    FF_TRY(step_strength_, DeviceBuffer::create(fluid_->context(), steps * targets * 4));
    strength_steps_ = steps;
  }
  std::vector<float> strength(steps * targets);
  for (std::size_t s = 0; s < steps; ++s)  // at the sub-step's start time, as the CPU controller's update_strengths
    for (std::size_t t = 0; t < targets; ++t)
      strength[s * targets + t] = samples_.strength(static_cast<std::uint8_t>(t), time + double(s) * double(dt));
  return step_strength_.upload(strength.data(), strength.size() * 4);
}

// A morph's swap (samples_ already hold the new sets): the samples' buffers again, and the passes bound to them. The
// submission before has finished with the old ones (PbfDevice::advance waits for it).
Status AdaptiveDevice::take_swap() {
  FF_CHECK(make_sample_buffers());
  pose_steps_ = 0;  // sized by the old sample count
  return make_kernels();
}

// Sub-steps [from, upto) of the frame, up to the next swap: a swap at `from` is taken first; moving targets' poses at
// each of them go into pose_pos_ and pose_vel_ (record_begin copies one in), the strengths of every sub-step of a
// timed scene into step_strength_ at the frame's first call.
Result<int> AdaptiveDevice::prepare_frame(double time, float dt, int from, int substeps) {
  if (substeps <= from) return substeps;
  const auto at = [&](int s) { return time + s * double(dt); };  // the sub-step's start, as the CPU solver's
  if (morphs_ && samples_.swaps_by(at(from))) {
    samples_.update(at(from), dt);
    swap_pending_ = true;
  }
  // Until the new set's buffers and passes all exist, the swap stays pending: a frame tried again after a failure
  // (serve steps the scene again) makes them again before anything is dispatched.
  if (swap_pending_) {
    FF_CHECK(take_swap());
    swap_pending_ = false;
  }
  int upto = from + 1;
  while (upto < substeps && !(morphs_ && samples_.swaps_by(at(upto)))) ++upto;
  const auto steps = static_cast<std::size_t>(substeps);
  if (timed_ && from == 0) FF_CHECK(prepare_strengths(time, dt, steps));
  if (!samples_.moving()) return upto;
  Context& c = fluid_->context();
  if (steps > pose_steps_) {
    FF_TRY(pose_pos_, DeviceBuffer::create(c, steps * m_ * 16));
    FF_TRY(pose_vel_, DeviceBuffer::create(c, steps * m_ * 16));
    FF_TRY(pose_nrm_, DeviceBuffer::create(c, steps * m_ * 16));
    pose_steps_ = steps;
  }
  const auto first = static_cast<std::size_t>(from), count = static_cast<std::size_t>(upto - from);
  std::vector<float> pos(4 * m_ * count, 0.0f), vel(4 * m_ * count, 0.0f), nrm(4 * m_ * count, 0.0f);
  for (std::size_t k = 0; k < count; ++k) {
    // As the CPU controller's begin_step: the samples at the sub-step's start time, u_c over the sub-step.
    samples_.update(at(from + static_cast<int>(k)), dt);
    for (std::size_t i = 0; i < m_; ++i) {
      std::memcpy(&pos[4 * (k * m_ + i)], samples_.position[i].data(), 12);
      std::memcpy(&vel[4 * (k * m_ + i)], samples_.velocity[i].data(), 12);
      std::memcpy(&nrm[4 * (k * m_ + i)], samples_.normal[i].data(), 12);  // the boundary normals turn too
    }
  }
  const VkDeviceSize bytes = pos.size() * 4, offset = first * m_ * 16;
  FF_CHECK(pose_pos_.upload(pos.data(), bytes, offset));
  FF_CHECK(pose_vel_.upload(vel.data(), bytes, offset));
  FF_CHECK(pose_nrm_.upload(nrm.data(), bytes, offset));
  return upto;
}

// The gather passes' own reading of c0, c1 and c3.y (shaders/control.glsl).
AdaptiveDevice::Constants AdaptiveDevice::gather_constants(float dt, int jump) const {
  Constants k = constants(dt);
  for (int a = 0; a < 3; ++a) k.c0[a] = ctx_.gravity[a];
  k.c0[3] = params_.gather_speed * ctx_.spacing();
  k.c1[0] = 1.0f / params_.gather_time, k.c1[1] = params_.gather_fill;
  k.c1[2] = params_.gather_chase, k.c1[3] = samples_.moving() && params_.follow > 0.0f ? 1.0f : 0.0f;
  k.c3[1] = jump;
  return k;
}

void AdaptiveDevice::record_seed_field(VkCommandBuffer cb, float dt) const {
  const std::size_t cells = field_.cells() * targets_;
  const Constants init = gather_constants(dt, 0);
  seed_init_k_.dispatch(cb, &init, groups(cells, 128));
  compute_barrier(cb);
  bool in_a = true;
  for (const int jump : jumps_) {
    const Constants k = gather_constants(dt, jump);
    (in_a ? flood_ab_k_ : flood_ba_k_).dispatch(cb, &k, groups(cells, 128));
    compute_barrier(cb);
    in_a = !in_a;
  }
  if (!in_a) {  // the last pass wrote seed_b_: the gather reads seed_a_
    const VkBufferCopy all{0, 0, cells * 4};
    vkCmdCopyBuffer(cb, seed_b_.handle(), seed_a_.handle(), 1, &all);
    compute_barrier(cb);
  }
}

void AdaptiveDevice::record_begin(VkCommandBuffer cb, float dt, int substep) const {
  if (timed_ && static_cast<std::size_t>(substep) < strength_steps_) {
    const VkDeviceSize bytes = samples_.targets() * 4;
    const VkBufferCopy slice{static_cast<VkDeviceSize>(substep) * bytes, 0, bytes};
    vkCmdCopyBuffer(cb, step_strength_.handle(), t_strength_.handle(), 1, &slice);
    compute_barrier(cb);
  }
  if (samples_.moving() && static_cast<std::size_t>(substep) < pose_steps_) {
    // This sub-step's pose into the samples' buffers, then the samples into their grids again.
    const VkBufferCopy slice{static_cast<VkDeviceSize>(substep) * m_ * 16, 0, m_ * 16};
    vkCmdCopyBuffer(cb, pose_pos_.handle(), s_pos_.handle(), 1, &slice);
    vkCmdCopyBuffer(cb, pose_vel_.handle(), s_vel_.handle(), 1, &slice);
    vkCmdCopyBuffer(cb, pose_nrm_.handle(), s_normal_.handle(), 1, &slice);
    compute_barrier(cb);
    fluid_->record_point_grid(cb, s_grid_);
    if (params_.gather) fluid_->record_point_grid(cb, s_field_);
  }
  const Constants k = constants(dt);
  fill_k_.dispatch(cb, &k, groups(m_, 128));
  compute_barrier(cb);
  bonds_k_.dispatch(cb, &k, groups(fluid_->size(), 128));
  compute_barrier(cb);
  if (params_.gather) record_seed_field(cb, dt);
}

void AdaptiveDevice::record_accelerations(VkCommandBuffer cb, float dt) const {
  const Constants k = accel_constants(dt);
  accel_k_.dispatch(cb, &k, groups(fluid_->size(), 256));
  compute_barrier(cb);
  if (params_.gather) {
    const Constants g = gather_constants(dt, 0);
    gather_k_.dispatch(cb, &g, groups(fluid_->size(), 256));
    compute_barrier(cb);
  }
}

void AdaptiveDevice::record_correction(VkCommandBuffer cb, int iteration, float dt) const {
  const Constants k = constants(dt);
  if (iteration == 0 && params_.bond_breaking && params_.gamma > 0.0f) {
    spring_k_.dispatch(cb, &k, groups(fluid_->size(), 128));
    compute_barrier(cb);
  }
  lambda_k_.dispatch(cb, &k, groups(m_, 128));
  compute_barrier(cb);
  correct_k_.dispatch(cb, &k, groups(fluid_->size(), 128));
  compute_barrier(cb);
}

}  // namespace ff::gpu
