#include "pipeline/stepper.h"

#include "control/steering.h"
#include "gpu/adaptive_device.h"
#include "gpu/context.h"
#include "gpu/pbf_device.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

namespace ff::pipeline {

Result<Device> parse_device(std::string_view name, std::string_view option) {
  if (name == "cpu") return Device::Cpu;
  if (name == "gpu") return Device::Gpu;
  if (name == "auto") return Device::Auto;
  return param_error(fmt::format("{} = '{}': expected cpu, gpu or auto", option, name));
}

namespace {

class CpuStepper final : public FrameStepper {
 public:
  CpuStepper(const sim::SolverParams& sp, const sim::Domain& dom, std::unique_ptr<sim::Controller> controller)
      : solver_(sp, dom), controller_(std::move(controller)) {}
  Result<sim::FrameStats> advance(sim::ParticleSet& p, double time, double frame_dt) override {
    return solver_.advance(p, time, frame_dt, *controller_);
  }
  std::string device() const override { return "cpu"; }
  std::string_view controller() const override { return controller_->name(); }
  Status set_target_pose(std::size_t t, const pose::Pose& pose) override {
    if (auto* s = control::steerable(*controller_)) s->set_target_pose(t, pose);
    return {};
  }

 private:
  sim::PbfSolver solver_;
  std::unique_ptr<sim::Controller> controller_;
};

class GpuStepper final : public FrameStepper {
 public:
  Result<sim::FrameStats> advance(sim::ParticleSet& p, double time, double frame_dt) override {
    if (p.size() != fluid_->size())
      return param_error(fmt::format("GPU: the run has {} particles, the device {}", p.size(), fluid_->size()));
    FF_TRY(const gpu::DeviceFrame f, fluid_->advance(solver_, time, frame_dt));
    FF_CHECK(fluid_->get_state(p.position, p.velocity));
    if (control_) {
      FF_CHECK(control_->get_bound(p.bound_control));
    } else {
      std::fill(p.bound_control.begin(), p.bound_control.end(), kInvalidIndex);
    }
    sim::FrameStats stats;
    stats.substeps = f.substeps;
    stats.dt = f.dt;
    stats.substeps_capped = f.capped;
    stats.max_speed = f.end_speed;  // the CPU's FrameStats: at the end of the frame
    stats.times.iterations = f.sweeps;
    stats.density_error_mean = f.density_error_mean;
    stats.density_error_max = f.density_error_max;
    return stats;
  }
  std::string device() const override { return name_; }
  std::string_view controller() const override { return control_ ? "adaptive" : "none"; }
  Status set_target_pose(std::size_t t, const pose::Pose& pose) override {
    return control_ ? control_->set_target_pose(t, pose) : Status{};
  }

  static Result<std::unique_ptr<GpuStepper>> create(int device_index, const sim::SolverParams& sp, const sim::Domain& dom,
                                                   const control::ControllerSpec& spec,
                                                   std::vector<control::ControlTarget> targets,
                                                   const control::ControlContext& ctx, const sim::ParticleSet& p) {
    std::unique_ptr<GpuStepper> s(new GpuStepper(sp, dom));
    FF_TRY(const gpu::FaultPlan faults, gpu::fault_plan_from_env());  // none unless a test asks (FF_GPU_FAULT)
    FF_TRY(s->context_, gpu::Context::create({.device = device_index, .validation = false}));
    s->context_->set_faults(faults);
    const gpu::DeviceInfo& info = s->context_->info();
    s->name_ = fmt::format("{} ({})", info.name, info.driver);
    FF_TRY(const gpu::GridSpec grid, gpu::GridSpec::for_support(dom.min, dom.max, s->solver_.lambda_consts().h));
    FF_TRY(s->fluid_, gpu::PbfDevice::create(*s->context_, p.size(), grid));
    FF_CHECK(s->fluid_->set_state(p.position, p.velocity));
    FF_CHECK(s->fluid_->set_ids(p.id));
    if (spec.name == "adaptive" && !targets.empty()) {
      FF_TRY(s->control_, gpu::AdaptiveDevice::create(*s->fluid_, std::move(targets), ctx,
                                                      spec.get<control::AdaptiveParams>()));
      FF_CHECK(s->control_->set_fluid_targets(p.target));
      s->fluid_->set_controller(s->control_.get());
    }
    return s;
  }

 private:
  GpuStepper(const sim::SolverParams& sp, const sim::Domain& dom) : solver_(sp, dom) {}
  sim::PbfSolver solver_;  // the constants and the sub-step plan; its own buffers stay empty
  std::unique_ptr<gpu::Context> context_;
  std::unique_ptr<gpu::PbfDevice> fluid_;
  std::unique_ptr<gpu::AdaptiveDevice> control_;
  std::string name_;
};

// What of the scene the GPU path does not do yet ("" when it does all of it).
std::string gpu_gap(const control::ControllerSpec& spec) {
  if (spec.name != "adaptive" && spec.name != "none") return fmt::format("the controller '{}'", spec.name);
  return {};
}

// The device index of the first discrete or integrated GPU (−1: none); with `any`, else the first with compute.
Result<int> pick_gpu(bool any) {
  FF_TRY(const std::vector<gpu::DeviceInfo> devices, gpu::list_devices());
  for (const gpu::DeviceInfo& d : devices)
    if (d.compute && (d.type == "discrete" || d.type == "integrated")) return d.index;
  if (any)
    for (const gpu::DeviceInfo& d : devices)
      if (d.compute) return d.index;
  return -1;
}

}  // namespace

bool auto_finds_gpu() {
  Result<int> index = pick_gpu(false);
  return index && *index >= 0;
}

Status check_device(Device device, const control::ControllerSpec& spec) {
  if (device != Device::Gpu) return {};
  std::string gap = gpu_gap(spec);
  if (!gap.empty()) return param_error("--device gpu: the GPU path does not do " + gap + " yet; use --device cpu");
  return {};
}

Result<std::unique_ptr<FrameStepper>> make_stepper(Device device, const sim::SolverParams& sp, const sim::Domain& dom,
                                                   const control::ControllerSpec& spec,
                                                   std::vector<control::ControlTarget> targets,
                                                   const control::ControlContext& ctx, const sim::ParticleSet& p) {
  if (device != Device::Cpu) {
    const std::string gap = gpu_gap(spec);
    auto index = pick_gpu(device == Device::Gpu);
    if (device == Device::Gpu) {
      FF_CHECK(check_device(device, spec));
      if (!index) return index.error();
      if (*index < 0) return io_error("--device gpu: no Vulkan device with a compute queue");
      FF_TRY(auto s, GpuStepper::create(*index, sp, dom, spec, std::move(targets), ctx, p));
      return std::unique_ptr<FrameStepper>(std::move(s));
    }
    if (!index || *index < 0) {
      spdlog::info("--device auto: no GPU ({}), running on the CPU", index ? "no discrete or integrated Vulkan device"
                                                                            : index.error().message);
    } else if (!gap.empty()) {
      spdlog::info("--device auto: the GPU path does not do {} yet, running on the CPU", gap);
    } else {
      auto s = GpuStepper::create(*index, sp, dom, spec, targets, ctx, p);
      if (s) return std::unique_ptr<FrameStepper>(std::move(*s));
      spdlog::info("--device auto: {}; running on the CPU", s.error().message);
    }
  }
  FF_TRY(auto controller, control::make_controller(spec, std::move(targets), ctx));
  return std::unique_ptr<FrameStepper>(new CpuStepper(sp, dom, std::move(controller)));
}

}  // namespace ff::pipeline
