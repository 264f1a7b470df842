#pragma once
// The Vulkan API as the GPU stage uses it: volk's function pointers (VK_NO_PROTOTYPES is set for the stage's users)
// and a VkResult as a word for error messages.
#include <volk.h>

#include <string>

namespace ff::gpu {

/// "VK_ERROR_OUT_OF_DEVICE_MEMORY" and the like (the Vulkan headers of Debian 12 have no string helper).
const char* vk_result_name(VkResult r);

}  // namespace ff::gpu
