// The Vulkan base (sim_gpu/vulkan_base) under the backend's own namespace: the solver, its
// callers and its tests name hapfluid::sim::vulkan::Context and the rest as before, and there is
// still one implementation of each.
#pragma once

#include "hapfluid/vk/buffer.hpp"
#include "hapfluid/vk/context.hpp"

namespace hapfluid::sim::vulkan {
using vk::Buffer;
using vk::check;
using vk::Context;
using vk::ContextOptions;
using vk::DeviceDescription;
using vk::DevicePreference;
using vk::list_devices;
using vk::MemoryUse;
using vk::parse_device_preference;
using vk::result_name;
using vk::TexelView;
using vk::ValidationCounts;
using vk::VulkanError;
using vk::VulkanUnavailable;
}  // namespace hapfluid::sim::vulkan
