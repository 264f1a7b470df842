#pragma once
// A Vulkan compute device: the instance, one device with one compute queue, a command pool, and what the GPU
// passes need from it (memory types, timestamp period). Everything the stage allocates hangs off a Context, which
// must outlive it.
//
// Validation: with `validation` set, the Khronos validation layer is enabled and every message of severity warning
// or error is kept (`messages()`): the tests require none. A machine without the layer gets an error saying so.
#include "core/error.h"
#include "gpu/vulkan.h"

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace ff::gpu {

/// One Vulkan physical device, as `fluidform devices` lists it.
struct DeviceInfo {
  int index = 0;              ///< order of vkEnumeratePhysicalDevices
  std::string name;           ///< "NVIDIA H100 80GB HBM3", "llvmpipe (LLVM 15.0.6, 256 bits)"
  std::string type;           ///< "discrete", "integrated", "virtual", "cpu", "other"
  std::string driver;         ///< driver name and info, e.g. "llvmpipe (Mesa 22.3.6 (LLVM 15.0.6))"
  std::string api;            ///< "1.3.230"
  std::uint64_t memory_bytes = 0;  ///< the largest device-local heap
  bool compute = false;       ///< has a queue family with compute
};

/// The Vulkan devices of this machine; an Error when there is no loader or no instance can be made.
Result<std::vector<DeviceInfo>> list_devices();

/// Faults injected at the Vulkan calls, to test what the runs do when a real device fails (issue 45): the call
/// returns an error code it can return, or the device reports a smaller limit than its own, and everything above it
/// takes its ordinary error path. Every GPU stepper (pipeline/stepper.h: run, compare, serve) reads them from
/// FF_GPU_FAULT (fault_plan_from_env) into its Context (set_faults); nothing is injected by default.
struct FaultPlan {
  long device_lost_at_submit = 0;  ///< the n-th queue submission (from 1) and every later one: VK_ERROR_DEVICE_LOST
  long oom_at_allocation = 0;      ///< the n-th buffer allocation (from 1): VK_ERROR_OUT_OF_DEVICE_MEMORY
  std::string bad_shader;          ///< loading this shader (e.g. "pbf_lambda"): VK_ERROR_INVALID_SHADER_NV
  long storage_buffers = 0;        ///< the device allows this many storage buffers per shader (a smaller GPU's limit)
};
/// FF_GPU_FAULT = "device-lost:N", "out-of-memory:N", "shader:NAME" or "storage-buffers:N" (unset or empty: none);
/// anything else is an error naming the variable.
Result<FaultPlan> fault_plan_from_env();

struct ContextOptions {
  int device = -1;          ///< index into list_devices(); −1: the first with a compute queue
  bool validation = false;  ///< enable VK_LAYER_KHRONOS_validation and keep its warnings and errors
};

class Context {
 public:
  static Result<std::unique_ptr<Context>> create(const ContextOptions& options);
  ~Context();
  Context(const Context&) = delete;
  Context& operator=(const Context&) = delete;

  const DeviceInfo& info() const { return info_; }
  VkDevice device() const { return device_; }
  VkQueue queue() const { return queue_; }
  VkCommandPool command_pool() const { return pool_; }
  float timestamp_period_ns() const { return timestamp_period_; }
  /// The most workgroups one dispatch may have along x (maxComputeWorkGroupCount[0]; 65535 on some devices).
  std::uint32_t max_groups() const { return max_groups_; }
  /// The most storage buffers one shader may bind: maxPerStageDescriptorStorageBuffers, or the descriptor set's
  /// limit where smaller. Vulkan guarantees only 4; the control passes bind 14 (lavapipe and desktop GPUs allow far more).
  std::uint32_t max_storage_buffers() const {
    return faults_.storage_buffers > 0 && faults_.storage_buffers < long(device_storage_buffers_)
               ? static_cast<std::uint32_t>(faults_.storage_buffers)
               : device_storage_buffers_;
  }
  /// Valid bits of the compute queue's timestamps (0: it has none).
  std::uint32_t timestamp_valid_bits() const { return timestamp_bits_; }
  /// A memory type among `type_bits` with all of `wanted`; −1 if none.
  int memory_type(std::uint32_t type_bits, VkMemoryPropertyFlags wanted) const;
  /// Validation messages (warnings and errors) so far, one line each.
  const std::vector<std::string>& messages() const { return messages_; }
  void add_message(std::string m) { messages_.push_back(std::move(m)); }

  /// Records commands into a one-time command buffer, submits it and waits for it.
  template <class Record>
  Status submit_and_wait(Record&& record);
  /// The injected result (FaultPlan) of the next buffer allocation, and of loading shader `name`: VK_SUCCESS unless
  /// a fault is planned there. A plan's storage-buffer limit also lowers max_storage_buffers().
  void set_faults(const FaultPlan& faults) { faults_ = faults; }  ///< none until set
  VkResult injected_allocation();
  VkResult injected_shader(const char* name) const;

 private:
  Context() = default;
  Status begin_one_shot(VkCommandBuffer& cb);
  Status end_one_shot(VkCommandBuffer cb);

  DeviceInfo info_;
  VkInstance instance_ = VK_NULL_HANDLE;
  VkDebugUtilsMessengerEXT messenger_ = VK_NULL_HANDLE;
  VkPhysicalDevice physical_ = VK_NULL_HANDLE;
  VkDevice device_ = VK_NULL_HANDLE;
  VkQueue queue_ = VK_NULL_HANDLE;
  std::uint32_t queue_family_ = 0;
  VkCommandPool pool_ = VK_NULL_HANDLE;
  VkFence fence_ = VK_NULL_HANDLE;
  VkPhysicalDeviceMemoryProperties memory_{};
  float timestamp_period_ = 0;
  std::uint32_t timestamp_bits_ = 0;
  std::uint32_t max_groups_ = 65535;
  std::uint32_t device_storage_buffers_ = 4;
  std::vector<std::string> messages_;
  FaultPlan faults_;
  long submits_ = 0, allocations_ = 0;
};

template <class Record>
Status Context::submit_and_wait(Record&& record) {
  VkCommandBuffer cb = VK_NULL_HANDLE;
  FF_CHECK(begin_one_shot(cb));
  record(cb);
  return end_one_shot(cb);
}

}  // namespace ff::gpu
