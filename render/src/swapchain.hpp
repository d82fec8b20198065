// The window's swapchain: FIFO present mode (always available, paced by the display), images
// usable as blit targets (the renderer's output), colour attachments (the overlay) and copy
// sources (screenshots). One "render done" semaphore per image.
#pragma once

#include <volk.h>
#define GLFW_INCLUDE_VULKAN
#include <GLFW/glfw3.h>

#include <vector>

#include "hapfluid/vk/context.hpp"

namespace hapfluid::render {

class Swapchain {
 public:
  Swapchain(vk::Context& ctx, VkSurfaceKHR surface, GLFWwindow* window);
  ~Swapchain() { destroy(); }
  Swapchain(const Swapchain&) = delete;
  Swapchain& operator=(const Swapchain&) = delete;

  void recreate(GLFWwindow* window) {
    destroy();
    create(window);
  }

  VkSwapchainKHR handle() const { return swapchain_; }
  VkFormat format() const { return format_; }
  VkExtent2D extent() const { return extent_; }
  VkImage image(uint32_t i) const { return images_[i]; }
  VkImageView view(uint32_t i) const { return views_[i]; }
  VkSemaphore render_done(uint32_t i) const { return render_done_[i]; }

 private:
  void create(GLFWwindow* window);
  void destroy();

  vk::Context& ctx_;
  VkSurfaceKHR surface_;
  VkSwapchainKHR swapchain_ = VK_NULL_HANDLE;
  VkFormat format_ = VK_FORMAT_UNDEFINED;
  VkColorSpaceKHR colour_space_{};
  VkExtent2D extent_{};
  std::vector<VkImage> images_;
  std::vector<VkImageView> views_;
  std::vector<VkSemaphore> render_done_;
};

}  // namespace hapfluid::render
