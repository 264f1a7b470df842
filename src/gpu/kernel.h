#pragma once
// The two objects every GPU pass is made of: storage buffers in device memory, and compute kernels (a SPIR-V
// module, its pipeline, and one descriptor set naming the buffers it reads and writes). A few large buffers per
// scene need no allocator library: each buffer has its own allocation.
#include "core/error.h"
#include "gpu/context.h"

#include <cstdint>
#include <initializer_list>
#include <span>

namespace ff::gpu {

/// A storage buffer in device-local memory; reached from the host by copies through a staging buffer.
class DeviceBuffer {
 public:
  DeviceBuffer() = default;
  ~DeviceBuffer();
  DeviceBuffer(DeviceBuffer&& o) noexcept;
  DeviceBuffer& operator=(DeviceBuffer&& o) noexcept;
  DeviceBuffer(const DeviceBuffer&) = delete;
  DeviceBuffer& operator=(const DeviceBuffer&) = delete;

  /// `bytes` (> 0) of device memory; `host_visible` asks for memory the host maps instead (staging).
  static Result<DeviceBuffer> create(Context& ctx, VkDeviceSize bytes, bool host_visible = false);
  VkBuffer handle() const { return buffer_; }
  VkDeviceSize bytes() const { return bytes_; }
  void* mapped() const { return mapped_; }

  /// Host → buffer and buffer → host, through a staging buffer (waits for the copy); a range past the end is an
  /// Error.
  Status upload(const void* data, VkDeviceSize bytes, VkDeviceSize offset = 0);
  Status download(void* data, VkDeviceSize bytes, VkDeviceSize offset = 0) const;

 private:
  void release();
  Status check_range(VkDeviceSize bytes, VkDeviceSize offset) const;
  Context* ctx_ = nullptr;
  VkBuffer buffer_ = VK_NULL_HANDLE;
  VkDeviceMemory memory_ = VK_NULL_HANDLE;
  VkDeviceSize bytes_ = 0;
  void* mapped_ = nullptr;
};

/// Push constants are one 128-byte block for every kernel (the least a Vulkan device must offer).
inline constexpr std::uint32_t kPushConstantBytes = 128;

/// A compute kernel bound to its buffers: binding b of the shader is buffers[b].
class Kernel {
 public:
  Kernel() = default;
  ~Kernel();
  Kernel(Kernel&& o) noexcept;
  Kernel& operator=(Kernel&& o) noexcept;
  Kernel(const Kernel&) = delete;
  Kernel& operator=(const Kernel&) = delete;

  static Result<Kernel> create(Context& ctx, const char* name, std::span<const std::uint32_t> spirv,
                               std::initializer_list<const DeviceBuffer*> buffers);
  /// Records push constants and a dispatch of `groups` workgroups (x only).
  void dispatch(VkCommandBuffer cb, const void* constants, std::uint32_t groups) const;

 private:
  void release();
  Context* ctx_ = nullptr;
  VkShaderModule module_ = VK_NULL_HANDLE;
  VkDescriptorSetLayout set_layout_ = VK_NULL_HANDLE;
  VkPipelineLayout layout_ = VK_NULL_HANDLE;
  VkPipeline pipeline_ = VK_NULL_HANDLE;
  VkDescriptorPool pool_ = VK_NULL_HANDLE;
  VkDescriptorSet set_ = VK_NULL_HANDLE;
};

/// A barrier between two dispatches (and buffer fills or copies): the writes of the first are visible to the second.
void compute_barrier(VkCommandBuffer cb);
/// A barrier after a copy into a host-visible buffer: its writes are visible to the host after the fence.
void host_barrier(VkCommandBuffer cb);

}  // namespace ff::gpu
