// GPU images with their memory (one allocation each: a handful of render targets do not need a
// sub-allocator), and the image barrier the passes use between each other. Buffers are the Vulkan
// base's (hapfluid/vk/buffer.hpp).
#pragma once

#include "hapfluid/vk/buffer.hpp"
#include "hapfluid/vk/context.hpp"

namespace hapfluid::render {

class GpuImage {
 public:
  GpuImage() = default;
  GpuImage(vk::Context& ctx, VkExtent2D extent, VkFormat format, VkImageUsageFlags usage,
           VkImageAspectFlags aspect = VK_IMAGE_ASPECT_COLOR_BIT);
  ~GpuImage();
  GpuImage(GpuImage&& other) noexcept { *this = std::move(other); }
  GpuImage& operator=(GpuImage&& other) noexcept;

  VkImage image() const { return image_; }
  VkImageView view() const { return view_; }
  VkFormat format() const { return format_; }
  VkExtent2D extent() const { return extent_; }
  VkImageAspectFlags aspect() const { return aspect_; }

 private:
  void release();
  vk::Context* ctx_ = nullptr;
  VkImage image_ = VK_NULL_HANDLE;
  VkDeviceMemory memory_ = VK_NULL_HANDLE;
  VkImageView view_ = VK_NULL_HANDLE;
  VkFormat format_ = VK_FORMAT_UNDEFINED;
  VkExtent2D extent_{};
  VkImageAspectFlags aspect_ = VK_IMAGE_ASPECT_COLOR_BIT;
};

struct ImageState {
  VkImageLayout layout;
  VkPipelineStageFlags2 stage;
  VkAccessFlags2 access;
};

// Commonly used states of an image between passes.
namespace state {
constexpr ImageState undefined{VK_IMAGE_LAYOUT_UNDEFINED, VK_PIPELINE_STAGE_2_TOP_OF_PIPE_BIT, 0};
constexpr ImageState colour_target{VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL,
                                   VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT,
                                   VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT | VK_ACCESS_2_COLOR_ATTACHMENT_READ_BIT};
constexpr ImageState depth_target{VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL,
                                  VK_PIPELINE_STAGE_2_EARLY_FRAGMENT_TESTS_BIT | VK_PIPELINE_STAGE_2_LATE_FRAGMENT_TESTS_BIT,
                                  VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT | VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_READ_BIT};
constexpr ImageState compute_read{VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
                                  VK_ACCESS_2_SHADER_SAMPLED_READ_BIT};
constexpr ImageState compute_write{VK_IMAGE_LAYOUT_GENERAL, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
                                   VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT};
constexpr ImageState transfer_src{VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT,
                                  VK_ACCESS_2_TRANSFER_READ_BIT};
constexpr ImageState transfer_dst{VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT,
                                  VK_ACCESS_2_TRANSFER_WRITE_BIT};
constexpr ImageState present{VK_IMAGE_LAYOUT_PRESENT_SRC_KHR, VK_PIPELINE_STAGE_2_BOTTOM_OF_PIPE_BIT, 0};
}  // namespace state

void transition(VkCommandBuffer cmd, VkImage image, VkImageAspectFlags aspect, const ImageState& from,
                const ImageState& to);
inline void transition(VkCommandBuffer cmd, const GpuImage& image, const ImageState& from, const ImageState& to) {
  transition(cmd, image.image(), image.aspect(), from, to);
}

}  // namespace hapfluid::render
