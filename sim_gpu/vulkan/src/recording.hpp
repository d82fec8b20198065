// Workgroup counts of the backend's passes. Internal to sim_gpu/vulkan.
#pragma once

#include <cstdint>

namespace hapfluid::sim::vulkan {

inline std::uint32_t groups(std::uint32_t threads, std::uint32_t local) { return (threads + local - 1) / local; }

}  // namespace hapfluid::sim::vulkan
