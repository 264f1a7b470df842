#pragma once
// One output frame of the simulation on the device the run chose (--device cpu|gpu|auto): the CPU solver with its
// controller, or the GPU's sub-steps (gpu/pbf_device.h, gpu/adaptive_device.h) with the particles brought back
// after every frame, since `run` writes and measures every frame. The run's loop (run.cpp) sees only this.
#include "control/control_context.h"
#include "control/control_targets.h"
#include "control/registry.h"
#include "core/error.h"
#include "pose/target_motion.h"
#include "sim/controller.h"
#include "sim/particle_set.h"
#include "sim/pbf_solver.h"

#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace ff::pipeline {

enum class Device { Cpu, Gpu, Auto };
/// "cpu", "gpu", "auto" (errors name `option`).
Result<Device> parse_device(std::string_view name, std::string_view option = "--device");

/// For --device gpu: an Error naming what of the scene the GPU path does not do yet (checked before the run starts
/// anything); ok for the CPU and auto.
Status check_device(Device device, const control::ControllerSpec& spec);

class FrameStepper {
 public:
  virtual ~FrameStepper() = default;
  /// One frame of `frame_dt` seconds from `time`: the particles advanced in place (positions, velocities and
  /// bound_control; densities only on the CPU).
  virtual Result<sim::FrameStats> advance(sim::ParticleSet& p, double time, double frame_dt) = 0;
  /// What ran: "cpu", or the GPU's name and driver.
  virtual std::string device() const = 0;
  virtual std::string_view controller() const = 0;
  /// Live steering (control/steering.h): target `t` holds `pose` from the next frame on. A controller without
  /// targets ignores it.
  virtual Status set_target_pose(std::size_t t, const pose::Pose& pose) = 0;
};

/// Whether `--device auto` finds a GPU to run on here: a discrete or integrated Vulkan device with a compute queue.
bool auto_finds_gpu();

/// The stepper for `device`. `spec.name` "none" runs plain PBF. GPU: the first discrete or integrated GPU, else any
/// Vulkan device (lavapipe on a machine without a GPU); a scene the GPU path does not do yet is a one-line error.
/// Auto: the GPU when there is a discrete or integrated one and the scene is one it does, else the CPU (said once,
/// as a note). The particles `p` are the run's start (uploaded to the GPU).
Result<std::unique_ptr<FrameStepper>> make_stepper(Device device, const sim::SolverParams& solver, const sim::Domain& domain,
                                                   const control::ControllerSpec& spec,
                                                   std::vector<control::ControlTarget> targets,
                                                   const control::ControlContext& ctx, const sim::ParticleSet& p);

}  // namespace ff::pipeline
