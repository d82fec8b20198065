// Backend choice for haptic-sim: `cpu` (the reference), `vulkan` (this backend; an error naming
// the cause when no Vulkan device is usable) or `auto` (a GPU if present, else lavapipe, else
// the CPU backend with a notice). The one entry point haptic-sim calls.
#pragma once

#include <ostream>

#include "hapfluid/sim/batch_run.hpp"
#include "hapfluid/sim_vulkan/base.hpp"

namespace hapfluid::sim::vulkan {

struct VulkanRunOptions {
  bool validation = false;                                // --vk-validation
  DevicePreference device = DevicePreference::automatic;  // --vk-device auto|gpu|cpu
};

// Batch mode on the Vulkan backend: the same outputs as run_batch (VTK frames, bodies.csv,
// couplings.csv, stats.json with "complete"), plus the device and the per-pass GPU split in
// stats.json. Throws VulkanUnavailable when no device can run it.
BatchResult run_batch_vulkan(const BatchOptions& options, const VulkanRunOptions& vulkan, std::ostream& progress);

// Dispatches on options.backend ("cpu", "vulkan", "auto"); throws std::runtime_error naming a
// backend it does not know.
BatchResult run_batch_on_backend(const BatchOptions& options, const VulkanRunOptions& vulkan, std::ostream& progress);

}  // namespace hapfluid::sim::vulkan
