#include "text_overlay.hpp"

#include <cstring>

#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wunused-function"
#include <stb_easy_font.h>
#pragma GCC diagnostic pop

#include "overlay_frag.spv.h"
#include "overlay_vert.spv.h"
#include "vk_pipelines.hpp"

namespace hapfluid::render {

TextOverlay::TextOverlay(vk::Context& ctx, VkFormat target_format) : ctx_(ctx) {
  layout_ = make_pipeline_layout(ctx.device(), VK_NULL_HANDLE, sizeof(glm::vec2), VK_SHADER_STAGE_VERTEX_BIT);
  GraphicsPipelineDesc d;
  d.vertex = HAPFLUID_SHADER(overlay_vert);
  d.fragment = HAPFLUID_SHADER(overlay_frag);
  d.bindings = {{0, sizeof(Vertex), VK_VERTEX_INPUT_RATE_VERTEX}};
  d.attributes = {{0, 0, VK_FORMAT_R32G32_SFLOAT, offsetof(Vertex, pixel)},
                  {1, 0, VK_FORMAT_R32G32B32A32_SFLOAT, offsetof(Vertex, colour)}};
  d.colour_formats = {target_format};
  VkPipelineColorBlendAttachmentState blend = no_blend();
  blend.blendEnable = VK_TRUE;  // translucent panel behind the text
  blend.srcColorBlendFactor = VK_BLEND_FACTOR_SRC_ALPHA;
  blend.dstColorBlendFactor = VK_BLEND_FACTOR_ONE_MINUS_SRC_ALPHA;
  blend.colorBlendOp = VK_BLEND_OP_ADD;
  blend.srcAlphaBlendFactor = VK_BLEND_FACTOR_ONE;
  blend.dstAlphaBlendFactor = VK_BLEND_FACTOR_ZERO;
  blend.alphaBlendOp = VK_BLEND_OP_ADD;
  d.blends = {blend};
  d.layout = layout_;
  pipeline_ = make_graphics_pipeline(ctx.device(), d);
  vertices_ = vk::Buffer(ctx, max_vertices * sizeof(Vertex), VK_BUFFER_USAGE_VERTEX_BUFFER_BIT, vk::MemoryUse::host);
  pending_.reserve(max_vertices);
}

TextOverlay::~TextOverlay() {
  vkDeviceWaitIdle(ctx_.device());
  vkDestroyPipeline(ctx_.device(), pipeline_, nullptr);
  vkDestroyPipelineLayout(ctx_.device(), layout_, nullptr);
}

void TextOverlay::clear() { pending_.clear(); }

void TextOverlay::rectangle(glm::vec2 a, glm::vec2 b, glm::vec4 colour) {
  if (pending_.size() + 6 > max_vertices) return;
  const glm::vec2 c[4] = {a, {b.x, a.y}, b, {a.x, b.y}};
  for (int i : {0, 1, 2, 0, 2, 3}) pending_.push_back({c[i], colour});
}

void TextOverlay::text(glm::vec2 pixel, const std::string& line, glm::vec4 colour) {
  // stb_easy_font emits quads of 4 vertices (x, y, z, rgba8); 2x scale for legibility.
  std::string copy = line;
  const int count = stb_easy_font_print(0, 0, copy.data(), nullptr, font_quads_.data(), int(font_quads_.size()));
  constexpr float scale = 2.0f;
  for (int q = 0; q < count; ++q) {
    float v[4][2];
    for (int k = 0; k < 4; ++k) std::memcpy(v[k], font_quads_.data() + (q * 4 + k) * 16, 2 * sizeof(float));
    rectangle(pixel + scale * glm::vec2(v[0][0], v[0][1]), pixel + scale * glm::vec2(v[2][0], v[2][1]), colour);
  }
}

void TextOverlay::record(VkCommandBuffer cmd, VkImageView target, VkExtent2D extent) {
  if (pending_.empty()) return;
  std::memcpy(vertices_.mapped(), pending_.data(), pending_.size() * sizeof(Vertex));
  VkRenderingAttachmentInfo colour{VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO};
  colour.imageView = target;
  colour.imageLayout = VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL;
  colour.loadOp = VK_ATTACHMENT_LOAD_OP_LOAD;
  colour.storeOp = VK_ATTACHMENT_STORE_OP_STORE;
  VkRenderingInfo info{VK_STRUCTURE_TYPE_RENDERING_INFO};
  info.renderArea = {{0, 0}, extent};
  info.layerCount = 1;
  info.colorAttachmentCount = 1;
  info.pColorAttachments = &colour;
  vkCmdBeginRendering(cmd, &info);
  VkViewport vp{0, 0, float(extent.width), float(extent.height), 0, 1};
  VkRect2D scissor{{0, 0}, extent};
  vkCmdSetViewport(cmd, 0, 1, &vp);
  vkCmdSetScissor(cmd, 0, 1, &scissor);
  vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, pipeline_);
  const glm::vec2 inv_size(1.0f / float(extent.width), 1.0f / float(extent.height));
  vkCmdPushConstants(cmd, layout_, VK_SHADER_STAGE_VERTEX_BIT, 0, sizeof inv_size, &inv_size);
  VkDeviceSize offset = 0;
  VkBuffer buffer = vertices_.handle();
  vkCmdBindVertexBuffers(cmd, 0, 1, &buffer, &offset);
  vkCmdDraw(cmd, uint32_t(pending_.size()), 1, 0, 0);
  vkCmdEndRendering(cmd);
}

}  // namespace hapfluid::render
