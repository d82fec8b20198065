// On-screen statistics for the windowed mode: text (stb_easy_font quads) and force bars, drawn
// over the swapchain image after the fluid frame was blitted to it.
#pragma once

#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "vk_resources.hpp"

namespace hapfluid::render {

class TextOverlay {
 public:
  TextOverlay(vk::Context& ctx, VkFormat target_format);
  ~TextOverlay();
  TextOverlay(const TextOverlay&) = delete;
  TextOverlay& operator=(const TextOverlay&) = delete;

  void clear();
  void text(glm::vec2 pixel, const std::string& line, glm::vec4 colour = glm::vec4(1.0f));
  void rectangle(glm::vec2 min_pixel, glm::vec2 max_pixel, glm::vec4 colour);
  // Draws onto `target` (in COLOR_ATTACHMENT_OPTIMAL layout) with its contents kept.
  void record(VkCommandBuffer cmd, VkImageView target, VkExtent2D extent);

 private:
  struct Vertex {
    glm::vec2 pixel;
    glm::vec4 colour;
  };
  vk::Context& ctx_;
  VkPipelineLayout layout_ = VK_NULL_HANDLE;
  VkPipeline pipeline_ = VK_NULL_HANDLE;
  vk::Buffer vertices_;
  std::vector<Vertex> pending_;
  std::vector<char> font_quads_ = std::vector<char>(64000);
  static constexpr size_t max_vertices = 60000;
};

}  // namespace hapfluid::render
