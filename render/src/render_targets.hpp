// The images one frame writes and reads, and the formats chosen for them at start-up from what
// the device supports (linear filtering, blending, storage).
#pragma once

#include <string>

#include "vk_resources.hpp"

namespace hapfluid::render {

struct TargetFormats {
  VkFormat scene_colour = VK_FORMAT_R8G8B8A8_UNORM;
  VkFormat scene_depth = VK_FORMAT_R32_SFLOAT;  // linear depth S_d, a colour target
  VkFormat zbuffer = VK_FORMAT_D32_SFLOAT;
  VkFormat splat = VK_FORMAT_R32G32_SFLOAT;     // (front, -back), MIN-blended, bilinear-sampled
  VkFormat smoothed = VK_FORMAT_R32_SFLOAT;     // filter ping-pong: storage + bilinear-sampled
  VkFormat normals = VK_FORMAT_R16G16B16A16_SFLOAT;  // view-space normals: storage + sampled
  VkFormat output = VK_FORMAT_R8G8B8A8_UNORM;   // composite result: storage + transfer source
  std::string summary;
};

// Throws std::runtime_error naming the format and the missing feature when nothing fits.
TargetFormats choose_formats(const vk::Context& ctx);

struct RenderTargets {
  RenderTargets(vk::Context& ctx, const TargetFormats& formats, VkExtent2D full, VkExtent2D half);
  VkExtent2D full, half;
  GpuImage scene_colour, scene_depth, zbuffer;  // full resolution
  GpuImage splat, smoothed_a, smoothed_b, normals;  // half resolution
  GpuImage output;                              // full resolution
};

}  // namespace hapfluid::render
