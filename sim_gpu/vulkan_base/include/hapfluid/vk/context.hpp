// The one Vulkan base of hapfluid, shared by the simulator's compute backend (sim_gpu/vulkan) and
// the renderer (render/): the loader (volk, loaded at run time, so a machine without libvulkan
// still runs the CPU backend), the instance with the Khronos validation layer on request, the
// choice of a physical device, the logical device with one queue, a command pool and one-time
// submissions.
//
// Two kinds of device: compute (Vulkan 1.2, a compute queue, a compute-only family preferred) and
// graphics (Vulkan 1.3 with dynamic rendering and synchronization2, a graphics+compute family,
// swapchain on request). Device choice for `auto`: a discrete GPU, else an integrated GPU, else
// another hardware type, else a CPU implementation (Mesa lavapipe). When nothing usable exists the
// constructor throws VulkanUnavailable with a message that says what is missing and how to fix
// it; the caller decides whether that is fatal or a fallback to the CPU.
#pragma once

#include <volk.h>

#include <atomic>
#include <cstdint>
#include <mutex>
#include <stdexcept>
#include <string>
#include <vector>

namespace hapfluid::vk {

// Any failure of a Vulkan call, with the call and the VkResult in the message.
class VulkanError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// No loader, no driver (ICD), or no device that can run the backend: a reason to fall back.
class VulkanUnavailable : public VulkanError {
 public:
  using VulkanError::VulkanError;
};

const char* result_name(VkResult result);
// Throws VulkanError("<what>: VK_ERROR_...") unless result is VK_SUCCESS.
void check(VkResult result, const char* what);

enum class DevicePreference {
  automatic,  // discrete > integrated > other hardware > CPU (lavapipe)
  gpu,        // hardware only: discrete or integrated (or virtual) GPU
  cpu,        // a CPU implementation only (lavapipe)
};
DevicePreference parse_device_preference(const std::string& text);  // "auto" | "gpu" | "cpu"

enum class QueueKind {
  compute,   // Vulkan 1.2, compute queue (the simulator)
  graphics,  // Vulkan 1.3, graphics+compute queue, dynamic rendering, synchronization2 (the renderer)
};

struct ContextOptions {
  std::string application = "hapfluid";
  QueueKind queue = QueueKind::compute;
  DevicePreference device = DevicePreference::automatic;
  std::vector<std::string> instance_extensions;  // e.g. what GLFW needs for a surface
  bool swapchain = false;                        // graphics: enable VK_KHR_swapchain on the device
  // Khronos validation layer plus a debug messenger that counts warnings and errors. Tests
  // always enable it; `haptic-sim --vk-validation`, `haptic-render --validation` (or, for the
  // renderer, HAPFLUID_VK_VALIDATION=1) enable it in a run.
  bool validation = false;
  // With validation: also the layer's synchronization validation (missing barriers between
  // passes are the bug class a compute pipeline is most prone to).
  bool synchronization_validation = true;
  // Print each validation message to stderr as it arrives (they are counted in any case).
  bool print_validation_messages = true;
};

struct DeviceDescription {
  std::string name;
  std::string type;             // "discrete GPU", "integrated GPU", "CPU", ...
  VkPhysicalDeviceType vk_type = VK_PHYSICAL_DEVICE_TYPE_OTHER;
  std::uint32_t api_version = 0;
  std::string driver;           // driver name and info, e.g. "llvmpipe Mesa 22.3.6 (LLVM 15.0.6)"
  bool has_compute_queue = false;
  bool has_graphics_compute_queue = false;
  std::string version_string() const;  // "1.3.230"
};

// Every physical device the loader reports (empty when Vulkan is unavailable, never throws
// VulkanUnavailable: for `--list-devices` and diagnostics).
std::vector<DeviceDescription> list_devices(std::string* why_empty = nullptr);

struct ValidationCounts {
  std::uint32_t warnings = 0;
  std::uint32_t errors = 0;
};

class Context {
 public:
  explicit Context(const ContextOptions& options);
  ~Context();
  Context(const Context&) = delete;
  Context& operator=(const Context&) = delete;

  VkInstance instance() const { return instance_; }
  VkPhysicalDevice physical_device() const { return physical_device_; }
  VkDevice device() const { return device_; }
  VkQueue queue() const { return queue_; }
  std::uint32_t queue_family() const { return queue_family_; }
  VkCommandPool command_pool() const { return command_pool_; }
  const VkPhysicalDeviceProperties& properties() const { return properties_; }
  const VkPhysicalDeviceMemoryProperties& memory_properties() const { return memory_properties_; }
  const DeviceDescription& description() const { return description_; }
  bool validation_enabled() const { return validation_; }

  // First memory type allowed by `type_bits` with all of `wanted`; throws VulkanError if none.
  std::uint32_t memory_type(std::uint32_t type_bits, VkMemoryPropertyFlags wanted) const;
  VkFormatFeatureFlags format_features(VkFormat format) const;  // optimal tiling

  // Timestamps on the context's queue (timestampValidBits > 0); period in ns per tick.
  bool timestamps_supported() const { return timestamp_valid_bits_ > 0; }
  double timestamp_period_ns() const { return properties_.limits.timestampPeriod; }
  std::uint32_t subgroup_size() const { return subgroup_size_; }

  // Warnings and errors reported by the validation layer since creation (0 without validation).
  ValidationCounts validation_counts() const;
  // The first messages (up to a few dozen), for test failure output.
  std::vector<std::string> validation_messages() const;

  // A one-time command buffer: record with fn, submit, wait (set-up uploads and read-backs).
  template <class Fn>
  void run_once(Fn&& fn) {
    VkCommandBuffer cb = begin_one_time();
    fn(cb);
    end_one_time(cb);
  }
  VkCommandBuffer begin_one_time();
  void end_one_time(VkCommandBuffer cb);

  // Destroys the device now (the destructor does it otherwise), so that what the validation layer
  // reports at device destruction (leaked objects) is counted while the counters can be read.
  void destroy_device();

  // Called by the debug messenger callback.
  void on_validation_message(VkDebugUtilsMessageSeverityFlagBitsEXT severity, const char* message);

 private:
  void create_instance(const ContextOptions& options);
  void choose_physical_device(const ContextOptions& options);
  void create_device(const ContextOptions& options);
  void release();

  bool validation_ = false;
  bool print_messages_ = true;
  QueueKind queue_kind_ = QueueKind::compute;
  VkInstance instance_ = VK_NULL_HANDLE;
  VkDebugUtilsMessengerEXT messenger_ = VK_NULL_HANDLE;
  VkPhysicalDevice physical_device_ = VK_NULL_HANDLE;
  VkDevice device_ = VK_NULL_HANDLE;
  VkQueue queue_ = VK_NULL_HANDLE;
  std::uint32_t queue_family_ = 0;
  std::uint32_t timestamp_valid_bits_ = 0;
  std::uint32_t subgroup_size_ = 0;
  VkCommandPool command_pool_ = VK_NULL_HANDLE;
  VkFence one_time_fence_ = VK_NULL_HANDLE;
  VkPhysicalDeviceProperties properties_{};
  VkPhysicalDeviceMemoryProperties memory_properties_{};
  DeviceDescription description_;

  std::atomic<std::uint32_t> warnings_{0}, errors_{0};
  mutable std::mutex messages_mutex_;
  std::vector<std::string> messages_;
};

}  // namespace hapfluid::vk
