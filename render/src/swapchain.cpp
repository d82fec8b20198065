#include "swapchain.hpp"

#include <algorithm>
#include <stdexcept>

namespace hapfluid::render {

Swapchain::Swapchain(vk::Context& ctx, VkSurfaceKHR surface, GLFWwindow* window) : ctx_(ctx), surface_(surface) {
  VkBool32 present = VK_FALSE;
  vkGetPhysicalDeviceSurfaceSupportKHR(ctx.physical_device(), ctx.queue_family(), surface, &present);
  if (!present) throw std::runtime_error("Vulkan: the graphics queue cannot present to this window");
  uint32_t count = 0;
  vkGetPhysicalDeviceSurfaceFormatsKHR(ctx.physical_device(), surface, &count, nullptr);
  std::vector<VkSurfaceFormatKHR> formats(count);
  vkGetPhysicalDeviceSurfaceFormatsKHR(ctx.physical_device(), surface, &count, formats.data());
  if (formats.empty()) throw std::runtime_error("Vulkan: the window surface offers no formats");
  format_ = formats[0].format;
  colour_space_ = formats[0].colorSpace;
  for (const auto& f : formats)
    if (f.format == VK_FORMAT_B8G8R8A8_UNORM || f.format == VK_FORMAT_R8G8B8A8_UNORM) {
      format_ = f.format;
      colour_space_ = f.colorSpace;
      break;
    }
  create(window);
}

void Swapchain::create(GLFWwindow* window) {
  // A minimised window has no pixels to present to: wait until it is restored (or closed).
  int fb_width = 0, fb_height = 0;
  glfwGetFramebufferSize(window, &fb_width, &fb_height);
  while ((fb_width == 0 || fb_height == 0) && !glfwWindowShouldClose(window)) {
    glfwWaitEvents();
    glfwGetFramebufferSize(window, &fb_width, &fb_height);
  }
  VkSurfaceCapabilitiesKHR caps;
  vk::check(vkGetPhysicalDeviceSurfaceCapabilitiesKHR(ctx_.physical_device(), surface_, &caps),
           "vkGetPhysicalDeviceSurfaceCapabilitiesKHR");
  const VkImageUsageFlags usage =
      VK_IMAGE_USAGE_TRANSFER_DST_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT | VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT;
  if ((caps.supportedUsageFlags & usage) != usage)
    throw std::runtime_error("Vulkan: swapchain images cannot be blit targets, copy sources and colour attachments here");
  extent_ = caps.currentExtent.width != UINT32_MAX ? caps.currentExtent
                                                   : VkExtent2D{uint32_t(fb_width), uint32_t(fb_height)};
  extent_.width = std::clamp(extent_.width, caps.minImageExtent.width, caps.maxImageExtent.width);
  extent_.height = std::clamp(extent_.height, caps.minImageExtent.height, caps.maxImageExtent.height);
  VkSwapchainCreateInfoKHR info{VK_STRUCTURE_TYPE_SWAPCHAIN_CREATE_INFO_KHR};
  info.surface = surface_;
  info.minImageCount = std::max(caps.minImageCount, 2u);
  if (caps.maxImageCount) info.minImageCount = std::min(info.minImageCount, caps.maxImageCount);
  info.imageFormat = format_;
  info.imageColorSpace = colour_space_;
  info.imageExtent = extent_;
  info.imageArrayLayers = 1;
  info.imageUsage = usage;
  info.imageSharingMode = VK_SHARING_MODE_EXCLUSIVE;
  info.preTransform = caps.currentTransform;
  info.compositeAlpha = VK_COMPOSITE_ALPHA_OPAQUE_BIT_KHR;
  info.presentMode = VK_PRESENT_MODE_FIFO_KHR;  // always available; paced by the display
  info.clipped = VK_TRUE;
  vk::check(vkCreateSwapchainKHR(ctx_.device(), &info, nullptr, &swapchain_), "vkCreateSwapchainKHR");
  uint32_t count = 0;
  vkGetSwapchainImagesKHR(ctx_.device(), swapchain_, &count, nullptr);
  images_.resize(count);
  vkGetSwapchainImagesKHR(ctx_.device(), swapchain_, &count, images_.data());
  for (VkImage image : images_) {
    VkImageViewCreateInfo v{VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
    v.image = image;
    v.viewType = VK_IMAGE_VIEW_TYPE_2D;
    v.format = format_;
    v.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
    VkImageView view;
    vk::check(vkCreateImageView(ctx_.device(), &v, nullptr, &view), "vkCreateImageView (swapchain)");
    views_.push_back(view);
  }
  VkSemaphoreCreateInfo s{VK_STRUCTURE_TYPE_SEMAPHORE_CREATE_INFO};
  render_done_.resize(count);
  for (auto& sem : render_done_) vk::check(vkCreateSemaphore(ctx_.device(), &s, nullptr, &sem), "vkCreateSemaphore");
}

void Swapchain::destroy() {
  vkDeviceWaitIdle(ctx_.device());
  for (VkImageView v : views_) vkDestroyImageView(ctx_.device(), v, nullptr);
  for (VkSemaphore s : render_done_) vkDestroySemaphore(ctx_.device(), s, nullptr);
  views_.clear();
  render_done_.clear();
  images_.clear();
  if (swapchain_) vkDestroySwapchainKHR(ctx_.device(), swapchain_, nullptr);
  swapchain_ = VK_NULL_HANDLE;
}

}  // namespace hapfluid::render
