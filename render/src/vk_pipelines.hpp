// Pipeline, layout and shader-module creation with the few knobs the passes need (vkguide's
// "pipelines" file). Shaders are SPIR-V arrays compiled at build time and embedded.
#pragma once

#include <vector>

#include "hapfluid/vk/context.hpp"

namespace hapfluid::render {

struct ShaderCode {
  const uint32_t* words;
  size_t bytes;
};
#define HAPFLUID_SHADER(symbol) ::hapfluid::render::ShaderCode{symbol, sizeof(symbol)}

struct GraphicsPipelineDesc {
  ShaderCode vertex{};
  ShaderCode fragment{};
  std::vector<VkVertexInputBindingDescription> bindings;
  std::vector<VkVertexInputAttributeDescription> attributes;
  VkPrimitiveTopology topology = VK_PRIMITIVE_TOPOLOGY_TRIANGLE_LIST;
  std::vector<VkFormat> colour_formats;
  std::vector<VkPipelineColorBlendAttachmentState> blends;  // empty: no blending, write all channels
  VkFormat depth_format = VK_FORMAT_UNDEFINED;
  bool depth_test = false;
  bool depth_write = false;
  VkPipelineLayout layout = VK_NULL_HANDLE;
};

VkPipeline make_graphics_pipeline(VkDevice device, const GraphicsPipelineDesc& desc);
VkPipeline make_compute_pipeline(VkDevice device, ShaderCode code, VkPipelineLayout layout);
VkDescriptorSetLayout make_set_layout(VkDevice device, const std::vector<VkDescriptorSetLayoutBinding>& bindings);
VkPipelineLayout make_pipeline_layout(VkDevice device, VkDescriptorSetLayout set_layout, uint32_t push_bytes,
                                      VkShaderStageFlags push_stages);

VkPipelineColorBlendAttachmentState no_blend();
// colour = min(src, dst), alpha = min(src, dst): the splat pass's front/back depth (§5.1).
VkPipelineColorBlendAttachmentState min_blend();

}  // namespace hapfluid::render
