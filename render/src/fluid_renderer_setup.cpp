#include <algorithm>
#include <cstring>

#include "fluid_renderer_impl.hpp"
#include "frame_uniforms.hpp"
#include "vk_pipelines.hpp"

#include "bilateral_filter_comp.spv.h"
#include "composite_comp.spv.h"
#include "scene_frag.spv.h"
#include "scene_vert.spv.h"
#include "spheres_frag.spv.h"
#include "surface_normals_comp.spv.h"
#include "spheres_vert.spv.h"
#include "splat_frag.spv.h"
#include "splat_vert.spv.h"

namespace hapfluid::render {
namespace {

VkDescriptorSetLayoutBinding binding(uint32_t index, VkDescriptorType type, VkShaderStageFlags stages) {
  return {index, type, 1, stages, nullptr};
}

}  // namespace

FluidRenderer::Impl::~Impl() {
  VkDevice d = ctx.device();
  vkDeviceWaitIdle(d);
  for (VkPipeline p : {scene_pipeline, spheres_pipeline, splat_pipeline, filter_pipeline, normals_pipeline,
                       composite_pipeline})
    vkDestroyPipeline(d, p, nullptr);
  for (VkPipelineLayout l : {scene_layout, spheres_layout, splat_layout, filter_layout, composite_layout})
    vkDestroyPipelineLayout(d, l, nullptr);
  for (VkDescriptorSetLayout l : {graphics_set_layout, filter_set_layout, composite_set_layout})
    vkDestroyDescriptorSetLayout(d, l, nullptr);
  vkDestroyDescriptorPool(d, pool, nullptr);
  vkDestroySampler(d, sampler, nullptr);
  vkDestroyFence(d, fence, nullptr);
  if (cmd) vkFreeCommandBuffers(d, ctx.command_pool(), 1, &cmd);
}

void FluidRenderer::Impl::ensure_capacity(vk::Buffer& buffer, size_t bytes, VkBufferUsageFlags usage) {
  if (buffer.size() >= bytes && buffer.handle()) return;
  vkQueueWaitIdle(ctx.queue());  // the old buffer may still be read by a windowed frame
  buffer = vk::Buffer(ctx, std::max<size_t>(bytes + bytes / 2, 256), usage, vk::MemoryUse::host);
}

void FluidRenderer::Impl::ensure_fluid_capacity(size_t particles) {
  if (particles <= fluid_capacity && fluid_particles.handle()) return;
  fluid_capacity = std::max<size_t>(particles + particles / 2, 1024);
  ensure_capacity(fluid_particles, fluid_capacity * sizeof(glm::vec3), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT);
  write_particle_binding();
}

void FluidRenderer::Impl::write_particle_binding() {
  VkDescriptorBufferInfo info{fluid_particles.handle(), 0, VK_WHOLE_SIZE};
  VkWriteDescriptorSet w{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
  w.dstSet = graphics_set;
  w.dstBinding = 1;
  w.descriptorCount = 1;
  w.descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
  w.pBufferInfo = &info;
  vkUpdateDescriptorSets(ctx.device(), 1, &w, 0, nullptr);
}

void FluidRenderer::Impl::create_buffers() {
  uniforms = vk::Buffer(ctx, sizeof(FrameUniforms), VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT, vk::MemoryUse::host);
  geometry = build_scene_geometry(scene);
  scene_vertices = vk::Buffer(ctx, std::max<size_t>(geometry.vertices.size() * sizeof(SceneVertex), 64),
                              VK_BUFFER_USAGE_VERTEX_BUFFER_BIT, vk::MemoryUse::host);
  std::memcpy(scene_vertices.mapped(), geometry.vertices.data(), geometry.vertices.size() * sizeof(SceneVertex));
  ensure_capacity(sphere_particles, 1024 * sizeof(glm::vec4), VK_BUFFER_USAGE_VERTEX_BUFFER_BIT);
  readback = vk::Buffer(ctx, VkDeviceSize(settings.width) * settings.height * 4, VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                        vk::MemoryUse::host);
  grid = {targets.half.width, targets.half.height};
  tile_buffer = vk::Buffer(ctx, VkDeviceSize(grid.tiles_x()) * grid.tiles_y() * sizeof(uint32_t),
                           VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, vk::MemoryUse::host);
  tile_marks.reserve(size_t(grid.tiles_x()) * grid.tiles_y());
  tiles.reserve(size_t(grid.tiles_x()) * grid.tiles_y());

  VkCommandBufferAllocateInfo alloc{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
  alloc.commandPool = ctx.command_pool();
  alloc.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
  alloc.commandBufferCount = 1;
  vk::check(vkAllocateCommandBuffers(ctx.device(), &alloc, &cmd), "vkAllocateCommandBuffers");
  VkFenceCreateInfo fence_info{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
  vk::check(vkCreateFence(ctx.device(), &fence_info, nullptr, &fence), "vkCreateFence");
}

void FluidRenderer::Impl::create_descriptors() {
  VkDevice d = ctx.device();
  VkSamplerCreateInfo s{VK_STRUCTURE_TYPE_SAMPLER_CREATE_INFO};
  s.magFilter = s.minFilter = VK_FILTER_LINEAR;  // the fig. 5 filter relies on bilinear averaging
  s.mipmapMode = VK_SAMPLER_MIPMAP_MODE_NEAREST;
  s.addressModeU = s.addressModeV = s.addressModeW = VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE;
  s.maxLod = 0.0f;
  vk::check(vkCreateSampler(d, &s, nullptr, &sampler), "vkCreateSampler");

  const VkShaderStageFlags vf = VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT;
  const VkShaderStageFlags cs = VK_SHADER_STAGE_COMPUTE_BIT;
  graphics_set_layout = make_set_layout(d, {binding(0, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, vf),
                                            binding(1, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, VK_SHADER_STAGE_VERTEX_BIT)});
  filter_set_layout = make_set_layout(d, {binding(0, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, cs),
                                          binding(1, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, cs),
                                          binding(2, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE, cs),
                                          binding(3, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, cs)});
  composite_set_layout = make_set_layout(d, {binding(0, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, cs),
                                             binding(1, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, cs),
                                             binding(2, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, cs),
                                             binding(3, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, cs),
                                             binding(4, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, cs),
                                             binding(5, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE, cs),
                                             binding(6, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, cs),
                                             binding(7, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, cs)});

  VkDescriptorPoolSize sizes[] = {{VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, 8},
                                  {VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 19},
                                  {VK_DESCRIPTOR_TYPE_STORAGE_IMAGE, 7},
                                  {VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 8}};
  VkDescriptorPoolCreateInfo p{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
  p.maxSets = 8;
  p.poolSizeCount = 4;
  p.pPoolSizes = sizes;
  vk::check(vkCreateDescriptorPool(d, &p, nullptr, &pool), "vkCreateDescriptorPool");
  auto allocate = [&](VkDescriptorSetLayout layout) {
    VkDescriptorSetAllocateInfo a{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
    a.descriptorPool = pool;
    a.descriptorSetCount = 1;
    a.pSetLayouts = &layout;
    VkDescriptorSet set;
    vk::check(vkAllocateDescriptorSets(d, &a, &set), "vkAllocateDescriptorSets");
    return set;
  };

  // Every binding of every set is written: lavapipe 22.3 crashes in its worker thread on a bound
  // set with an unwritten binding, and the validation layer does not report it.
  VkDescriptorBufferInfo ubo{uniforms.handle(), 0, sizeof(FrameUniforms)};
  auto write_ubo = [&](VkDescriptorSet set) {
    VkWriteDescriptorSet w{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
    w.dstSet = set;
    w.dstBinding = 0;
    w.descriptorCount = 1;
    w.descriptorType = VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER;
    w.pBufferInfo = &ubo;
    vkUpdateDescriptorSets(d, 1, &w, 0, nullptr);
  };
  VkDescriptorBufferInfo tile_info{tile_buffer.handle(), 0, VK_WHOLE_SIZE};
  auto write_tiles = [&](VkDescriptorSet set, uint32_t b) {
    VkWriteDescriptorSet w{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
    w.dstSet = set;
    w.dstBinding = b;
    w.descriptorCount = 1;
    w.descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
    w.pBufferInfo = &tile_info;
    vkUpdateDescriptorSets(d, 1, &w, 0, nullptr);
  };
  auto write_image = [&](VkDescriptorSet set, uint32_t b, const GpuImage& image, bool storage) {
    VkDescriptorImageInfo info{storage ? VK_NULL_HANDLE : sampler, image.view(),
                               storage ? VK_IMAGE_LAYOUT_GENERAL : VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL};
    VkWriteDescriptorSet w{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
    w.dstSet = set;
    w.dstBinding = b;
    w.descriptorCount = 1;
    w.descriptorType = storage ? VK_DESCRIPTOR_TYPE_STORAGE_IMAGE : VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
    w.pImageInfo = &info;
    vkUpdateDescriptorSets(d, 1, &w, 0, nullptr);
  };

  graphics_set = allocate(graphics_set_layout);
  write_ubo(graphics_set);
  ensure_fluid_capacity(1024);  // also writes binding 1
  const GpuImage* filter_io[3][2] = {{&targets.splat, &targets.smoothed_a},
                                     {&targets.smoothed_a, &targets.smoothed_b},
                                     {&targets.smoothed_b, &targets.smoothed_a}};
  for (int i = 0; i < 3; ++i) {
    filter_sets[i] = allocate(filter_set_layout);
    write_ubo(filter_sets[i]);
    write_image(filter_sets[i], 1, *filter_io[i][0], false);
    write_image(filter_sets[i], 2, *filter_io[i][1], true);
    write_tiles(filter_sets[i], 3);
  }
  normals_set = allocate(filter_set_layout);
  write_ubo(normals_set);
  write_image(normals_set, 1, final_smoothed(), false);
  write_image(normals_set, 2, targets.normals, true);
  write_tiles(normals_set, 3);
  const GpuImage* smoothed[3] = {&targets.splat, &targets.smoothed_a, &targets.smoothed_b};
  for (int i = 0; i < 3; ++i) {
    composite_sets[i] = allocate(composite_set_layout);
    write_ubo(composite_sets[i]);
    write_image(composite_sets[i], 1, targets.scene_colour, false);
    write_image(composite_sets[i], 2, targets.scene_depth, false);
    write_image(composite_sets[i], 3, *smoothed[i], false);
    write_image(composite_sets[i], 4, targets.splat, false);
    write_image(composite_sets[i], 5, targets.output, true);
    write_tiles(composite_sets[i], 6);
    write_image(composite_sets[i], 7, targets.normals, false);
  }
}

void FluidRenderer::Impl::create_pipelines() {
  VkDevice d = ctx.device();
  const VkShaderStageFlags vf = VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT;
  scene_layout = make_pipeline_layout(d, graphics_set_layout, sizeof(ScenePush), vf);
  spheres_layout = make_pipeline_layout(d, graphics_set_layout, sizeof(glm::vec4), vf);
  splat_layout = make_pipeline_layout(d, graphics_set_layout, 0, 0);
  filter_layout = make_pipeline_layout(d, filter_set_layout, 0, 0);
  composite_layout = make_pipeline_layout(d, composite_set_layout, sizeof(CompositePush), VK_SHADER_STAGE_COMPUTE_BIT);

  GraphicsPipelineDesc scene_desc;
  scene_desc.vertex = HAPFLUID_SHADER(scene_vert);
  scene_desc.fragment = HAPFLUID_SHADER(scene_frag);
  scene_desc.bindings = {{0, sizeof(SceneVertex), VK_VERTEX_INPUT_RATE_VERTEX}};
  scene_desc.attributes = {{0, 0, VK_FORMAT_R32G32B32_SFLOAT, offsetof(SceneVertex, position_m)},
                           {1, 0, VK_FORMAT_R32G32B32_SFLOAT, offsetof(SceneVertex, normal)}};
  scene_desc.colour_formats = {formats.scene_colour, formats.scene_depth};
  scene_desc.depth_format = formats.zbuffer;
  scene_desc.depth_test = scene_desc.depth_write = true;
  scene_desc.layout = scene_layout;
  scene_pipeline = make_graphics_pipeline(d, scene_desc);

  GraphicsPipelineDesc spheres_desc = scene_desc;
  spheres_desc.vertex = HAPFLUID_SHADER(spheres_vert);
  spheres_desc.fragment = HAPFLUID_SHADER(spheres_frag);
  spheres_desc.bindings = {{0, sizeof(glm::vec4), VK_VERTEX_INPUT_RATE_INSTANCE}};
  spheres_desc.attributes = {{0, 0, VK_FORMAT_R32G32B32A32_SFLOAT, 0}};
  spheres_desc.topology = VK_PRIMITIVE_TOPOLOGY_TRIANGLE_STRIP;
  spheres_desc.layout = spheres_layout;
  spheres_pipeline = make_graphics_pipeline(d, spheres_desc);

  GraphicsPipelineDesc splat_desc;
  splat_desc.vertex = HAPFLUID_SHADER(splat_vert);
  splat_desc.fragment = HAPFLUID_SHADER(splat_frag);
  splat_desc.topology = VK_PRIMITIVE_TOPOLOGY_TRIANGLE_LIST;
  splat_desc.colour_formats = {formats.splat};
  splat_desc.blends = {min_blend()};
  splat_desc.layout = splat_layout;
  splat_pipeline = make_graphics_pipeline(d, splat_desc);

  filter_pipeline = make_compute_pipeline(d, HAPFLUID_SHADER(bilateral_filter_comp), filter_layout);
  // Same bindings as the filter: UBO, source depth, target image, tiles.
  normals_pipeline = make_compute_pipeline(d, HAPFLUID_SHADER(surface_normals_comp), filter_layout);
  composite_pipeline = make_compute_pipeline(d, HAPFLUID_SHADER(composite_comp), composite_layout);
}

}  // namespace hapfluid::render
