// The Vulkan instance, device and queue the renderer runs on (vkguide's "init" step), loaded
// through volk. With validation on, VK_LAYER_KHRONOS_validation is enabled and a debug-utils
// messenger counts every warning and error, so tests can fail on any of them.
#pragma once

#include <volk.h>

#include <atomic>
#include <mutex>
#include <string>
#include <vector>

namespace hapfluid::render {

// Throws std::runtime_error("Vulkan: <what> failed: <VkResult>") on any result but VK_SUCCESS.
void vk_check(VkResult result, const char* what);
const char* to_string(VkResult result);

struct ContextOptions {
  bool validation = false;                       // also on when HAPFLUID_VK_VALIDATION=1
  std::vector<std::string> instance_extensions;  // e.g. what GLFW needs for a surface
  bool swapchain = false;                        // enable VK_KHR_swapchain on the device
};

class VulkanContext {
 public:
  explicit VulkanContext(const ContextOptions& options);
  ~VulkanContext();
  VulkanContext(const VulkanContext&) = delete;
  VulkanContext& operator=(const VulkanContext&) = delete;

  VkInstance instance() const { return instance_; }
  VkPhysicalDevice physical_device() const { return physical_; }
  VkDevice device() const { return device_; }
  VkQueue queue() const { return queue_; }
  uint32_t queue_family() const { return queue_family_; }
  VkCommandPool command_pool() const { return command_pool_; }
  const VkPhysicalDeviceProperties& properties() const { return properties_; }
  bool validation_enabled() const { return validation_; }
  bool timestamps_supported() const { return timestamp_valid_bits_ > 0; }

  uint32_t memory_type(uint32_t type_bits, VkMemoryPropertyFlags wanted) const;
  VkFormatFeatureFlags format_features(VkFormat format) const;  // optimal tiling

  // Records with `record`, submits and waits (uploads, read-backs, tests).
  template <typename Record>
  void run_once(Record&& record) {
    VkCommandBuffer cmd = begin_one_time();
    record(cmd);
    end_one_time(cmd);
  }
  VkCommandBuffer begin_one_time();
  void end_one_time(VkCommandBuffer cmd);

  // Destroys the device now (the destructor does it otherwise), so that what the validation layer
  // reports at device destruction (leaked objects) is counted while the counters can be read.
  void destroy_device();

  int validation_warnings() const { return warnings_.load(); }
  int validation_errors() const { return errors_.load(); }
  std::vector<std::string> validation_messages() const;

 private:
  static VKAPI_ATTR VkBool32 VKAPI_CALL on_message(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                                   VkDebugUtilsMessageTypeFlagsEXT type,
                                                   const VkDebugUtilsMessengerCallbackDataEXT* data, void* self);
  void create_instance(const ContextOptions& options);
  void pick_device();
  void create_device(bool swapchain);

  bool validation_ = false;
  VkInstance instance_ = VK_NULL_HANDLE;
  VkDebugUtilsMessengerEXT messenger_ = VK_NULL_HANDLE;
  VkPhysicalDevice physical_ = VK_NULL_HANDLE;
  VkPhysicalDeviceProperties properties_{};
  VkPhysicalDeviceMemoryProperties memory_{};
  uint32_t queue_family_ = 0;
  uint32_t timestamp_valid_bits_ = 0;
  VkDevice device_ = VK_NULL_HANDLE;
  VkQueue queue_ = VK_NULL_HANDLE;
  VkCommandPool command_pool_ = VK_NULL_HANDLE;

  std::atomic<int> warnings_{0}, errors_{0};
  mutable std::mutex messages_mutex_;
  std::vector<std::string> messages_;
};

}  // namespace hapfluid::render
