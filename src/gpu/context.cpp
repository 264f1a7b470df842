#include "gpu/context.h"

#include <fmt/format.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>

namespace ff::gpu {

const char* vk_result_name(VkResult r) {
  switch (r) {
    case VK_SUCCESS: return "VK_SUCCESS";
    case VK_NOT_READY: return "VK_NOT_READY";
    case VK_TIMEOUT: return "VK_TIMEOUT";
    case VK_INCOMPLETE: return "VK_INCOMPLETE";
    case VK_ERROR_OUT_OF_HOST_MEMORY: return "VK_ERROR_OUT_OF_HOST_MEMORY";
    case VK_ERROR_OUT_OF_DEVICE_MEMORY: return "VK_ERROR_OUT_OF_DEVICE_MEMORY";
    case VK_ERROR_INITIALIZATION_FAILED: return "VK_ERROR_INITIALIZATION_FAILED";
    case VK_ERROR_DEVICE_LOST: return "VK_ERROR_DEVICE_LOST";
    case VK_ERROR_MEMORY_MAP_FAILED: return "VK_ERROR_MEMORY_MAP_FAILED";
    case VK_ERROR_LAYER_NOT_PRESENT: return "VK_ERROR_LAYER_NOT_PRESENT";
    case VK_ERROR_EXTENSION_NOT_PRESENT: return "VK_ERROR_EXTENSION_NOT_PRESENT";
    case VK_ERROR_FEATURE_NOT_PRESENT: return "VK_ERROR_FEATURE_NOT_PRESENT";
    case VK_ERROR_INCOMPATIBLE_DRIVER: return "VK_ERROR_INCOMPATIBLE_DRIVER";
    case VK_ERROR_TOO_MANY_OBJECTS: return "VK_ERROR_TOO_MANY_OBJECTS";
    case VK_ERROR_FORMAT_NOT_SUPPORTED: return "VK_ERROR_FORMAT_NOT_SUPPORTED";
    case VK_ERROR_FRAGMENTED_POOL: return "VK_ERROR_FRAGMENTED_POOL";
    case VK_ERROR_OUT_OF_POOL_MEMORY: return "VK_ERROR_OUT_OF_POOL_MEMORY";
    case VK_ERROR_INVALID_SHADER_NV: return "VK_ERROR_INVALID_SHADER_NV";
    default: return "VkResult (unnamed)";
  }
}

namespace {

Error vk_error(const char* what, VkResult r) {
  const std::string m = fmt::format("Vulkan: {} failed ({})", what, vk_result_name(r));
  // A lost device or exhausted memory is the machine's state, not the user's input.
  return r == VK_ERROR_OUT_OF_DEVICE_MEMORY || r == VK_ERROR_OUT_OF_HOST_MEMORY || r == VK_ERROR_DEVICE_LOST
             ? numerical_error(m)
             : io_error(m);
}

const char* type_name(VkPhysicalDeviceType t) {
  switch (t) {
    case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU: return "discrete";
    case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU: return "integrated";
    case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU: return "virtual";
    case VK_PHYSICAL_DEVICE_TYPE_CPU: return "cpu";
    default: return "other";
  }
}

constexpr const char* kValidationLayer = "VK_LAYER_KHRONOS_validation";

// The loader is opened once per process (volk keeps its entry points in globals of its own: they are the same
// for every instance, so sharing them is harmless).
Status load_loader() {
  static const VkResult r = volkInitialize();
  if (r != VK_SUCCESS)
    return io_error("Vulkan: no loader (libvulkan.so.1) on this machine (Debian: libvulkan1 and a driver such as "
                    "mesa-vulkan-drivers)");
  return {};
}

bool has_layer(const char* name) {
  std::uint32_t n = 0;
  vkEnumerateInstanceLayerProperties(&n, nullptr);
  std::vector<VkLayerProperties> layers(n);
  vkEnumerateInstanceLayerProperties(&n, layers.data());
  return std::any_of(layers.begin(), layers.end(), [&](const VkLayerProperties& l) { return std::strcmp(l.layerName, name) == 0; });
}

Result<VkInstance> make_instance(bool validation) {
  FF_CHECK(load_loader());
  VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO};
  app.pApplicationName = "fluidform";
  app.pEngineName = "fluidform";
  app.apiVersion = VK_API_VERSION_1_1;
  std::vector<const char*> layers, extensions;
  if (validation) {
    if (!has_layer(kValidationLayer))
      return io_error("Vulkan: the validation layer VK_LAYER_KHRONOS_validation is not installed (Debian: "
                      "vulkan-validationlayers)");
    layers.push_back(kValidationLayer);
    extensions.push_back(VK_EXT_DEBUG_UTILS_EXTENSION_NAME);
  }
  VkInstanceCreateInfo ci{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
  ci.pApplicationInfo = &app;
  ci.enabledLayerCount = static_cast<std::uint32_t>(layers.size());
  ci.ppEnabledLayerNames = layers.data();
  ci.enabledExtensionCount = static_cast<std::uint32_t>(extensions.size());
  ci.ppEnabledExtensionNames = extensions.data();
  VkInstance instance = VK_NULL_HANDLE;
  if (const VkResult r = vkCreateInstance(&ci, nullptr, &instance); r != VK_SUCCESS) {
    if (r == VK_ERROR_INCOMPATIBLE_DRIVER)
      return io_error("Vulkan: no Vulkan device on this machine (no driver answered; Debian's mesa-vulkan-drivers has "
                      "one on the CPU)");
    return vk_error("vkCreateInstance", r);
  }
  volkLoadInstanceOnly(instance);
  return instance;
}

std::vector<VkPhysicalDevice> physical_devices(VkInstance instance) {
  std::uint32_t n = 0;
  vkEnumeratePhysicalDevices(instance, &n, nullptr);
  std::vector<VkPhysicalDevice> out(n);
  vkEnumeratePhysicalDevices(instance, &n, out.data());
  out.resize(n);
  return out;
}

// The first queue family with compute, or −1.
int compute_family(VkPhysicalDevice pd) {
  std::uint32_t n = 0;
  vkGetPhysicalDeviceQueueFamilyProperties(pd, &n, nullptr);
  std::vector<VkQueueFamilyProperties> families(n);
  vkGetPhysicalDeviceQueueFamilyProperties(pd, &n, families.data());
  for (std::uint32_t f = 0; f < n; ++f)
    if (families[f].queueFlags & VK_QUEUE_COMPUTE_BIT) return static_cast<int>(f);
  return -1;
}

DeviceInfo describe(VkPhysicalDevice pd, int index) {
  VkPhysicalDeviceDriverProperties driver{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_DRIVER_PROPERTIES};
  VkPhysicalDeviceProperties2 props{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2};
  VkPhysicalDeviceProperties base{};
  // Driver properties are Vulkan 1.2 (or VK_KHR_driver_properties); on an older device only the base properties.
  if (vkGetPhysicalDeviceProperties2) {
    vkGetPhysicalDeviceProperties(pd, &base);
    if (base.apiVersion >= VK_API_VERSION_1_2) props.pNext = &driver;
    vkGetPhysicalDeviceProperties2(pd, &props);
    base = props.properties;
  } else {
    vkGetPhysicalDeviceProperties(pd, &base);
  }
  DeviceInfo d;
  d.index = index;
  d.name = base.deviceName;
  d.type = type_name(base.deviceType);
  d.api = fmt::format("{}.{}.{}", VK_API_VERSION_MAJOR(base.apiVersion), VK_API_VERSION_MINOR(base.apiVersion),
                      VK_API_VERSION_PATCH(base.apiVersion));
  d.driver = driver.driverName[0] ? fmt::format("{} ({})", driver.driverName, driver.driverInfo)
                                  : fmt::format("driver version {:#x}", base.driverVersion);
  VkPhysicalDeviceMemoryProperties mem{};
  vkGetPhysicalDeviceMemoryProperties(pd, &mem);
  for (std::uint32_t h = 0; h < mem.memoryHeapCount; ++h)
    if (mem.memoryHeaps[h].flags & VK_MEMORY_HEAP_DEVICE_LOCAL_BIT)
      d.memory_bytes = std::max<std::uint64_t>(d.memory_bytes, mem.memoryHeaps[h].size);
  d.compute = compute_family(pd) >= 0;
  return d;
}

VKAPI_ATTR VkBool32 VKAPI_CALL on_message(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                          VkDebugUtilsMessageTypeFlagsEXT, const VkDebugUtilsMessengerCallbackDataEXT* data,
                                          void* user) {
  if (severity >= VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT)
    static_cast<Context*>(user)->add_message(data && data->pMessage ? data->pMessage : "(no text)");
  return VK_FALSE;
}

}  // namespace

Result<std::vector<DeviceInfo>> list_devices() {
  FF_TRY(VkInstance instance, make_instance(false));
  std::vector<DeviceInfo> out;
  int i = 0;
  for (VkPhysicalDevice pd : physical_devices(instance)) out.push_back(describe(pd, i++));
  vkDestroyInstance(instance, nullptr);
  return out;
}

Result<std::unique_ptr<Context>> Context::create(const ContextOptions& options) {
  std::unique_ptr<Context> c(new Context());
  FF_TRY(c->instance_, make_instance(options.validation));
  if (options.validation) {
    VkDebugUtilsMessengerCreateInfoEXT mi{VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT};
    mi.messageSeverity = VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
    mi.messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT |
                     VK_DEBUG_UTILS_MESSAGE_TYPE_PERFORMANCE_BIT_EXT;
    mi.pfnUserCallback = on_message;
    mi.pUserData = c.get();
    if (const VkResult r = vkCreateDebugUtilsMessengerEXT(c->instance_, &mi, nullptr, &c->messenger_); r != VK_SUCCESS)
      return vk_error("vkCreateDebugUtilsMessengerEXT", r);
  }
  const std::vector<VkPhysicalDevice> devices = physical_devices(c->instance_);
  if (devices.empty()) return io_error("Vulkan: no Vulkan device on this machine");
  int pick = options.device;
  if (pick < 0) {
    for (std::size_t i = 0; i < devices.size() && pick < 0; ++i)
      if (compute_family(devices[i]) >= 0) pick = static_cast<int>(i);
    if (pick < 0) return io_error("Vulkan: no device with a compute queue");
  } else if (pick >= static_cast<int>(devices.size())) {
    return param_error(fmt::format("Vulkan: no device {} (this machine has {}; see fluidform devices)", pick, devices.size()));
  }
  c->physical_ = devices[static_cast<std::size_t>(pick)];
  c->info_ = describe(c->physical_, pick);
  const int family = compute_family(c->physical_);
  if (family < 0) return io_error(fmt::format("Vulkan: device {} ({}) has no compute queue", pick, c->info_.name));
  c->queue_family_ = static_cast<std::uint32_t>(family);

  const float priority = 1.0f;
  VkDeviceQueueCreateInfo qi{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
  qi.queueFamilyIndex = c->queue_family_;
  qi.queueCount = 1;
  qi.pQueuePriorities = &priority;
  VkDeviceCreateInfo di{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO};
  di.queueCreateInfoCount = 1;
  di.pQueueCreateInfos = &qi;
  if (const VkResult r = vkCreateDevice(c->physical_, &di, nullptr, &c->device_); r != VK_SUCCESS)
    return vk_error("vkCreateDevice", r);
  volkLoadDevice(c->device_);
  vkGetDeviceQueue(c->device_, c->queue_family_, 0, &c->queue_);
  VkCommandPoolCreateInfo pi{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
  pi.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
  pi.queueFamilyIndex = c->queue_family_;
  if (const VkResult r = vkCreateCommandPool(c->device_, &pi, nullptr, &c->pool_); r != VK_SUCCESS)
    return vk_error("vkCreateCommandPool", r);
  VkFenceCreateInfo fi{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
  if (const VkResult r = vkCreateFence(c->device_, &fi, nullptr, &c->fence_); r != VK_SUCCESS)
    return vk_error("vkCreateFence", r);
  vkGetPhysicalDeviceMemoryProperties(c->physical_, &c->memory_);
  VkPhysicalDeviceProperties props{};
  vkGetPhysicalDeviceProperties(c->physical_, &props);
  c->timestamp_period_ = props.limits.timestampPeriod;
  c->max_groups_ = props.limits.maxComputeWorkGroupCount[0];
  c->device_storage_buffers_ =
      std::min(props.limits.maxPerStageDescriptorStorageBuffers, props.limits.maxDescriptorSetStorageBuffers);
  std::uint32_t nf = 0;
  vkGetPhysicalDeviceQueueFamilyProperties(c->physical_, &nf, nullptr);
  std::vector<VkQueueFamilyProperties> families(nf);
  vkGetPhysicalDeviceQueueFamilyProperties(c->physical_, &nf, families.data());
  c->timestamp_bits_ = families[c->queue_family_].timestampValidBits;
  return c;
}

VkResult Context::injected_allocation() {
  ++allocations_;
  return allocations_ == faults_.oom_at_allocation ? VK_ERROR_OUT_OF_DEVICE_MEMORY : VK_SUCCESS;
}

VkResult Context::injected_shader(const char* name) const {
  return !faults_.bad_shader.empty() && faults_.bad_shader == name ? VK_ERROR_INVALID_SHADER_NV : VK_SUCCESS;
}

Result<FaultPlan> fault_plan_from_env() {
  const char* env = std::getenv("FF_GPU_FAULT");
  FaultPlan plan;
  if (!env || !*env) return plan;
  const std::string v = env;
  const auto colon = v.find(':');
  const std::string kind = v.substr(0, colon), arg = colon == std::string::npos ? "" : v.substr(colon + 1);
  char* end = nullptr;
  const long n = std::strtol(arg.c_str(), &end, 10);
  const bool count = !arg.empty() && end && *end == '\0' && n > 0;
  if (kind == "device-lost" && count) plan.device_lost_at_submit = n;
  else if (kind == "out-of-memory" && count) plan.oom_at_allocation = n;
  else if (kind == "shader" && !arg.empty()) plan.bad_shader = arg;
  else if (kind == "storage-buffers" && count) plan.storage_buffers = n;
  else
    return param_error(fmt::format(
        "FF_GPU_FAULT = '{}': expected device-lost:N, out-of-memory:N, shader:NAME or storage-buffers:N", v));
  return plan;
}

Context::~Context() {
  if (device_) {
    vkDeviceWaitIdle(device_);
    if (fence_) vkDestroyFence(device_, fence_, nullptr);
    if (pool_) vkDestroyCommandPool(device_, pool_, nullptr);
    vkDestroyDevice(device_, nullptr);
  }
  if (messenger_) vkDestroyDebugUtilsMessengerEXT(instance_, messenger_, nullptr);
  if (instance_) vkDestroyInstance(instance_, nullptr);
}

int Context::memory_type(std::uint32_t type_bits, VkMemoryPropertyFlags wanted) const {
  for (std::uint32_t t = 0; t < memory_.memoryTypeCount; ++t)
    if ((type_bits & (1u << t)) && (memory_.memoryTypes[t].propertyFlags & wanted) == wanted) return static_cast<int>(t);
  return -1;
}

Status Context::begin_one_shot(VkCommandBuffer& cb) {
  VkCommandBufferAllocateInfo ai{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
  ai.commandPool = pool_;
  ai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
  ai.commandBufferCount = 1;
  if (const VkResult r = vkAllocateCommandBuffers(device_, &ai, &cb); r != VK_SUCCESS)
    return vk_error("vkAllocateCommandBuffers", r);
  VkCommandBufferBeginInfo bi{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
  bi.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
  if (const VkResult r = vkBeginCommandBuffer(cb, &bi); r != VK_SUCCESS) return vk_error("vkBeginCommandBuffer", r);
  return {};
}

Status Context::end_one_shot(VkCommandBuffer cb) {
  Status s;
  if (const VkResult r = vkEndCommandBuffer(cb); r != VK_SUCCESS) s = vk_error("vkEndCommandBuffer", r);
  if (s.ok()) {
    VkSubmitInfo si{VK_STRUCTURE_TYPE_SUBMIT_INFO};
    si.commandBufferCount = 1;
    si.pCommandBuffers = &cb;
    ++submits_;
    const bool lost = faults_.device_lost_at_submit > 0 && submits_ >= faults_.device_lost_at_submit;
    if (const VkResult r = lost ? VK_ERROR_DEVICE_LOST : vkQueueSubmit(queue_, 1, &si, fence_); r != VK_SUCCESS) {
      s = vk_error("vkQueueSubmit", r);
    } else {
      if (const VkResult w = vkWaitForFences(device_, 1, &fence_, VK_TRUE, UINT64_MAX); w != VK_SUCCESS)
        s = vk_error("vkWaitForFences", w);
      vkResetFences(device_, 1, &fence_);
    }
  }
  vkFreeCommandBuffers(device_, pool_, 1, &cb);
  return s;
}

}  // namespace ff::gpu
