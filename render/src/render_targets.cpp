#include "render_targets.hpp"

#include <stdexcept>
#include <vector>

namespace hapfluid::render {
namespace {

const char* name(VkFormat f) {
  switch (f) {
    case VK_FORMAT_R32G32_SFLOAT: return "RG32F";
    case VK_FORMAT_R16G16_SFLOAT: return "RG16F";
    case VK_FORMAT_R32_SFLOAT: return "R32F";
    case VK_FORMAT_R16_SFLOAT: return "R16F";
    case VK_FORMAT_R16G16B16A16_SFLOAT: return "RGBA16F";
    case VK_FORMAT_R32G32B32A32_SFLOAT: return "RGBA32F";
    case VK_FORMAT_R8G8B8A8_UNORM: return "RGBA8";
    case VK_FORMAT_D32_SFLOAT: return "D32F";
    default: return "?";
  }
}

VkFormat first_with(const vk::Context& ctx, const std::vector<VkFormat>& candidates, VkFormatFeatureFlags need,
                    const char* role) {
  for (VkFormat f : candidates)
    if ((ctx.format_features(f) & need) == need) return f;
  std::string tried;
  for (VkFormat f : candidates) tried += std::string(tried.empty() ? "" : ", ") + name(f);
  throw std::runtime_error(std::string("Vulkan: no format for the ") + role + " (tried " + tried +
                           ") supports the features it needs on this device");
}

}  // namespace

TargetFormats choose_formats(const vk::Context& ctx) {
  TargetFormats t;
  const VkFormatFeatureFlags sampled_linear =
      VK_FORMAT_FEATURE_SAMPLED_IMAGE_BIT | VK_FORMAT_FEATURE_SAMPLED_IMAGE_FILTER_LINEAR_BIT;
  // The splat target is bilinear-sampled by the fig. 5 filter, so linear filtering is a must;
  // 32-bit keeps sub-millimetre depth at metres of distance, 16-bit is the fallback.
  t.splat = first_with(ctx, {VK_FORMAT_R32G32_SFLOAT, VK_FORMAT_R16G16_SFLOAT},
                       sampled_linear | VK_FORMAT_FEATURE_COLOR_ATTACHMENT_BLEND_BIT, "splat depth target");
  t.smoothed = first_with(ctx, {VK_FORMAT_R32_SFLOAT, VK_FORMAT_R16_SFLOAT},
                          sampled_linear | VK_FORMAT_FEATURE_STORAGE_IMAGE_BIT, "smoothed depth");
  t.normals = first_with(ctx, {VK_FORMAT_R16G16B16A16_SFLOAT, VK_FORMAT_R32G32B32A32_SFLOAT},
                         VK_FORMAT_FEATURE_STORAGE_IMAGE_BIT | VK_FORMAT_FEATURE_SAMPLED_IMAGE_BIT, "normals");
  t.scene_colour = first_with(ctx, {VK_FORMAT_R8G8B8A8_UNORM}, sampled_linear | VK_FORMAT_FEATURE_COLOR_ATTACHMENT_BIT,
                              "scene colour");
  t.scene_depth = first_with(ctx, {VK_FORMAT_R32_SFLOAT, VK_FORMAT_R16_SFLOAT},
                             VK_FORMAT_FEATURE_SAMPLED_IMAGE_BIT | VK_FORMAT_FEATURE_COLOR_ATTACHMENT_BIT,
                             "scene linear depth");
  t.zbuffer = first_with(ctx, {VK_FORMAT_D32_SFLOAT, VK_FORMAT_D24_UNORM_S8_UINT},
                         VK_FORMAT_FEATURE_DEPTH_STENCIL_ATTACHMENT_BIT, "depth buffer");
  t.output = first_with(ctx, {VK_FORMAT_R8G8B8A8_UNORM},
                        VK_FORMAT_FEATURE_STORAGE_IMAGE_BIT | VK_FORMAT_FEATURE_TRANSFER_SRC_BIT |
                            VK_FORMAT_FEATURE_TRANSFER_DST_BIT | VK_FORMAT_FEATURE_BLIT_SRC_BIT,
                        "output image");
  t.summary = std::string("splat ") + name(t.splat) + " (blend+linear), filter " + name(t.smoothed) +
              " (storage+linear), scene depth " + name(t.scene_depth);
  return t;
}

RenderTargets::RenderTargets(vk::Context& ctx, const TargetFormats& f, VkExtent2D full_extent, VkExtent2D half_extent)
    : full(full_extent), half(half_extent) {
  const VkImageUsageFlags sampled = VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT;
  scene_colour = GpuImage(ctx, full, f.scene_colour, VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | sampled);
  scene_depth = GpuImage(ctx, full, f.scene_depth, VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | sampled);
  zbuffer = GpuImage(ctx, full, f.zbuffer, VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT, VK_IMAGE_ASPECT_DEPTH_BIT);
  splat = GpuImage(ctx, half, f.splat, VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | sampled);
  const VkImageUsageFlags cleared = VK_IMAGE_USAGE_STORAGE_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT | sampled;
  smoothed_a = GpuImage(ctx, half, f.smoothed, cleared);
  smoothed_b = GpuImage(ctx, half, f.smoothed, cleared);
  normals = GpuImage(ctx, half, f.normals, VK_IMAGE_USAGE_STORAGE_BIT | VK_IMAGE_USAGE_SAMPLED_BIT);
  output = GpuImage(ctx, full, f.output,
                    VK_IMAGE_USAGE_STORAGE_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT);
}

}  // namespace hapfluid::render
