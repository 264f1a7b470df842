#include "gpu/kernel.h"

#include <fmt/format.h>

#include <cstring>
#include <utility>
#include <vector>

namespace ff::gpu {

namespace {

Error vk_fail(const std::string& what, VkResult r) {
  const std::string m = fmt::format("Vulkan: {} failed ({})", what, vk_result_name(r));
  return r == VK_ERROR_OUT_OF_DEVICE_MEMORY || r == VK_ERROR_OUT_OF_HOST_MEMORY || r == VK_ERROR_DEVICE_LOST
             ? numerical_error(m)
             : io_error(m);
}

}  // namespace

DeviceBuffer::~DeviceBuffer() { release(); }

DeviceBuffer::DeviceBuffer(DeviceBuffer&& o) noexcept
    : ctx_(std::exchange(o.ctx_, nullptr)),
      buffer_(std::exchange(o.buffer_, VK_NULL_HANDLE)),
      memory_(std::exchange(o.memory_, VK_NULL_HANDLE)),
      bytes_(std::exchange(o.bytes_, 0)),
      mapped_(std::exchange(o.mapped_, nullptr)) {}

DeviceBuffer& DeviceBuffer::operator=(DeviceBuffer&& o) noexcept {
  if (this != &o) {
    release();
    ctx_ = std::exchange(o.ctx_, nullptr);
    buffer_ = std::exchange(o.buffer_, VK_NULL_HANDLE);
    memory_ = std::exchange(o.memory_, VK_NULL_HANDLE);
    bytes_ = std::exchange(o.bytes_, 0);
    mapped_ = std::exchange(o.mapped_, nullptr);
  }
  return *this;
}

void DeviceBuffer::release() {
  if (!ctx_) return;
  if (buffer_) vkDestroyBuffer(ctx_->device(), buffer_, nullptr);
  if (memory_) vkFreeMemory(ctx_->device(), memory_, nullptr);  // unmaps too
  buffer_ = VK_NULL_HANDLE;
  memory_ = VK_NULL_HANDLE;
  mapped_ = nullptr;
  ctx_ = nullptr;
}

Result<DeviceBuffer> DeviceBuffer::create(Context& ctx, VkDeviceSize bytes, bool host_visible) {
  DeviceBuffer b;
  b.ctx_ = &ctx;
  b.bytes_ = bytes;
  VkBufferCreateInfo bi{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
  bi.size = bytes;
  bi.usage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_SRC_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT;
  bi.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
  if (const VkResult r = vkCreateBuffer(ctx.device(), &bi, nullptr, &b.buffer_); r != VK_SUCCESS)
    return vk_fail("vkCreateBuffer", r);
  VkMemoryRequirements req{};
  vkGetBufferMemoryRequirements(ctx.device(), b.buffer_, &req);
  const VkMemoryPropertyFlags wanted = host_visible
                                           ? VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT
                                           : VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT;
  int type = ctx.memory_type(req.memoryTypeBits, wanted);
  if (type < 0 && !host_visible) type = ctx.memory_type(req.memoryTypeBits, 0);
  if (type < 0) return io_error("Vulkan: no memory type for a storage buffer on " + ctx.info().name);
  VkMemoryAllocateInfo ai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
  ai.allocationSize = req.size;
  ai.memoryTypeIndex = static_cast<std::uint32_t>(type);
  VkResult alloc = ctx.injected_allocation();  // VK_SUCCESS unless a test plans a fault here (gpu::FaultPlan)
  if (alloc == VK_SUCCESS) alloc = vkAllocateMemory(ctx.device(), &ai, nullptr, &b.memory_);
  if (alloc != VK_SUCCESS)
    return vk_fail(fmt::format("allocating {:.3g} MB of device memory", static_cast<double>(bytes) / 1e6), alloc);
  if (const VkResult r = vkBindBufferMemory(ctx.device(), b.buffer_, b.memory_, 0); r != VK_SUCCESS)
    return vk_fail("vkBindBufferMemory", r);
  if (host_visible)
    if (const VkResult r = vkMapMemory(ctx.device(), b.memory_, 0, VK_WHOLE_SIZE, 0, &b.mapped_); r != VK_SUCCESS)
      return vk_fail("vkMapMemory", r);
  return b;
}

// A copy past the buffer's end is refused before it is recorded (the driver would not: it is undefined behaviour).
Status DeviceBuffer::check_range(VkDeviceSize bytes, VkDeviceSize offset) const {
  if (offset > bytes_ || bytes > bytes_ - offset)
    return param_error(
        fmt::format("GPU: {} bytes at offset {} do not fit a buffer of {} bytes", bytes, offset, bytes_));
  return {};
}

Status DeviceBuffer::upload(const void* data, VkDeviceSize bytes, VkDeviceSize offset) {
  if (bytes == 0) return {};
  FF_CHECK(check_range(bytes, offset));
  FF_TRY(DeviceBuffer staging, create(*ctx_, bytes, true));
  std::memcpy(staging.mapped(), data, bytes);
  return ctx_->submit_and_wait([&](VkCommandBuffer cb) {
    compute_barrier(cb);  // after the device's earlier writes and reads of the buffer
    const VkBufferCopy region{0, offset, bytes};
    vkCmdCopyBuffer(cb, staging.handle(), buffer_, 1, &region);
    compute_barrier(cb);  // before the passes of later submissions read it
  });
}

Status DeviceBuffer::download(void* data, VkDeviceSize bytes, VkDeviceSize offset) const {
  if (bytes == 0) return {};
  FF_CHECK(check_range(bytes, offset));
  FF_TRY(DeviceBuffer staging, create(*ctx_, bytes, true));
  FF_CHECK(ctx_->submit_and_wait([&](VkCommandBuffer cb) {
    compute_barrier(cb);  // the passes' writes, before the copy reads them
    const VkBufferCopy region{offset, 0, bytes};
    vkCmdCopyBuffer(cb, buffer_, staging.handle(), 1, &region);
    host_barrier(cb);  // the copy's writes, visible to the host once the fence has signalled
  }));
  std::memcpy(data, staging.mapped(), bytes);
  return {};
}

Kernel::~Kernel() { release(); }

Kernel::Kernel(Kernel&& o) noexcept
    : ctx_(std::exchange(o.ctx_, nullptr)),
      module_(std::exchange(o.module_, VK_NULL_HANDLE)),
      set_layout_(std::exchange(o.set_layout_, VK_NULL_HANDLE)),
      layout_(std::exchange(o.layout_, VK_NULL_HANDLE)),
      pipeline_(std::exchange(o.pipeline_, VK_NULL_HANDLE)),
      pool_(std::exchange(o.pool_, VK_NULL_HANDLE)),
      set_(std::exchange(o.set_, VK_NULL_HANDLE)) {}

Kernel& Kernel::operator=(Kernel&& o) noexcept {
  if (this != &o) {
    release();
    ctx_ = std::exchange(o.ctx_, nullptr);
    module_ = std::exchange(o.module_, VK_NULL_HANDLE);
    set_layout_ = std::exchange(o.set_layout_, VK_NULL_HANDLE);
    layout_ = std::exchange(o.layout_, VK_NULL_HANDLE);
    pipeline_ = std::exchange(o.pipeline_, VK_NULL_HANDLE);
    pool_ = std::exchange(o.pool_, VK_NULL_HANDLE);
    set_ = std::exchange(o.set_, VK_NULL_HANDLE);
  }
  return *this;
}

void Kernel::release() {
  if (!ctx_) return;
  const VkDevice d = ctx_->device();
  if (pipeline_) vkDestroyPipeline(d, pipeline_, nullptr);
  if (layout_) vkDestroyPipelineLayout(d, layout_, nullptr);
  if (pool_) vkDestroyDescriptorPool(d, pool_, nullptr);  // frees the set
  if (set_layout_) vkDestroyDescriptorSetLayout(d, set_layout_, nullptr);
  if (module_) vkDestroyShaderModule(d, module_, nullptr);
  ctx_ = nullptr;
}

Result<Kernel> Kernel::create(Context& ctx, const char* name, std::span<const std::uint32_t> spirv,
                              std::initializer_list<const DeviceBuffer*> buffers) {
  Kernel k;
  k.ctx_ = &ctx;
  const VkDevice d = ctx.device();
  VkShaderModuleCreateInfo mi{VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO};
  mi.codeSize = spirv.size_bytes();
  mi.pCode = spirv.data();
  VkResult loaded = ctx.injected_shader(name);  // VK_SUCCESS unless a test plans a fault here (gpu::FaultPlan)
  if (loaded == VK_SUCCESS) loaded = vkCreateShaderModule(d, &mi, nullptr, &k.module_);
  if (loaded != VK_SUCCESS) return vk_fail(fmt::format("loading shader {}", name), loaded);

  const auto n = static_cast<std::uint32_t>(buffers.size());
  // A device that allows fewer storage buffers per shader than a pass binds cannot run it: said in one line before
  // any frame is made (Vulkan's own error for it is undefined behaviour, or a validation message at best).
  if (n > ctx.max_storage_buffers())
    return io_error(fmt::format("Vulkan: shader {} binds {} storage buffers and {} allows {} per shader "
                                "(its storage-buffer limit; the CPU runs it: --device cpu)",
                                name, n, ctx.info().name, ctx.max_storage_buffers()));
  std::vector<VkDescriptorSetLayoutBinding> bindings(n);
  for (std::uint32_t b = 0; b < n; ++b)
    bindings[b] = {b, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr};
  VkDescriptorSetLayoutCreateInfo li{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
  li.bindingCount = n;
  li.pBindings = bindings.data();
  if (const VkResult r = vkCreateDescriptorSetLayout(d, &li, nullptr, &k.set_layout_); r != VK_SUCCESS)
    return vk_fail("vkCreateDescriptorSetLayout", r);
  const VkPushConstantRange push{VK_SHADER_STAGE_COMPUTE_BIT, 0, kPushConstantBytes};
  VkPipelineLayoutCreateInfo pli{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
  pli.setLayoutCount = 1;
  pli.pSetLayouts = &k.set_layout_;
  pli.pushConstantRangeCount = 1;
  pli.pPushConstantRanges = &push;
  if (const VkResult r = vkCreatePipelineLayout(d, &pli, nullptr, &k.layout_); r != VK_SUCCESS)
    return vk_fail("vkCreatePipelineLayout", r);
  VkComputePipelineCreateInfo ci{VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO};
  ci.stage = {VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO};
  ci.stage.stage = VK_SHADER_STAGE_COMPUTE_BIT;
  ci.stage.module = k.module_;
  ci.stage.pName = "main";
  ci.layout = k.layout_;
  if (const VkResult r = vkCreateComputePipelines(d, VK_NULL_HANDLE, 1, &ci, nullptr, &k.pipeline_); r != VK_SUCCESS)
    return vk_fail(fmt::format("building the pipeline of shader {}", name), r);

  const VkDescriptorPoolSize size{VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, n};
  VkDescriptorPoolCreateInfo pi{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
  pi.maxSets = 1;
  pi.poolSizeCount = 1;
  pi.pPoolSizes = &size;
  if (const VkResult r = vkCreateDescriptorPool(d, &pi, nullptr, &k.pool_); r != VK_SUCCESS)
    return vk_fail("vkCreateDescriptorPool", r);
  VkDescriptorSetAllocateInfo ai{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
  ai.descriptorPool = k.pool_;
  ai.descriptorSetCount = 1;
  ai.pSetLayouts = &k.set_layout_;
  if (const VkResult r = vkAllocateDescriptorSets(d, &ai, &k.set_); r != VK_SUCCESS)
    return vk_fail("vkAllocateDescriptorSets", r);
  std::vector<VkDescriptorBufferInfo> infos;
  infos.reserve(n);
  for (const DeviceBuffer* b : buffers) infos.push_back({b->handle(), 0, VK_WHOLE_SIZE});
  std::vector<VkWriteDescriptorSet> writes(n);
  for (std::uint32_t b = 0; b < n; ++b) {
    writes[b] = {VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
    writes[b].dstSet = k.set_;
    writes[b].dstBinding = b;
    writes[b].descriptorCount = 1;
    writes[b].descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
    writes[b].pBufferInfo = &infos[b];
  }
  vkUpdateDescriptorSets(d, n, writes.data(), 0, nullptr);
  return k;
}

void Kernel::dispatch(VkCommandBuffer cb, const void* constants, std::uint32_t groups) const {
  vkCmdBindPipeline(cb, VK_PIPELINE_BIND_POINT_COMPUTE, pipeline_);
  vkCmdBindDescriptorSets(cb, VK_PIPELINE_BIND_POINT_COMPUTE, layout_, 0, 1, &set_, 0, nullptr);
  vkCmdPushConstants(cb, layout_, VK_SHADER_STAGE_COMPUTE_BIT, 0, kPushConstantBytes, constants);
  if (groups > 0) vkCmdDispatch(cb, groups, 1, 1);
}

void host_barrier(VkCommandBuffer cb) {
  VkMemoryBarrier mb{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
  mb.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
  mb.dstAccessMask = VK_ACCESS_HOST_READ_BIT;
  vkCmdPipelineBarrier(cb, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_HOST_BIT, 0, 1, &mb, 0, nullptr, 0, nullptr);
}

void compute_barrier(VkCommandBuffer cb) {
  VkMemoryBarrier mb{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
  mb.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_TRANSFER_WRITE_BIT;
  mb.dstAccessMask = VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_TRANSFER_READ_BIT |
                     VK_ACCESS_TRANSFER_WRITE_BIT;
  vkCmdPipelineBarrier(cb, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT,
                       VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT, 0, 1, &mb, 0, nullptr,
                       0, nullptr);
}

}  // namespace ff::gpu
