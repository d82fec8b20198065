#include "hapfluid/render/fluid_renderer.hpp"

#include <algorithm>
#include <cstring>
#include <stdexcept>

#include <glm/gtc/matrix_transform.hpp>

#include "fluid_tiles.hpp"
#include "frame_uniforms.hpp"
#include "gpu_timer.hpp"
#include "render_targets.hpp"
#include "scene_geometry.hpp"
#include "vk_pipelines.hpp"

#include "bilateral_filter_comp.spv.h"
#include "composite_comp.spv.h"
#include "scene_frag.spv.h"
#include "scene_vert.spv.h"
#include "spheres_frag.spv.h"
#include "spheres_vert.spv.h"
#include "splat_frag.spv.h"
#include "splat_vert.spv.h"

namespace hapfluid::render {
namespace {

struct ScenePush {
  glm::mat4 model;
  glm::vec4 colour;
  glm::vec4 params;
};
struct CompositePush {
  int32_t mode;
  float thickness_scale_m;
};

VkDescriptorSetLayoutBinding binding(uint32_t index, VkDescriptorType type, VkShaderStageFlags stages) {
  return {index, type, 1, stages, nullptr};
}

void set_viewport(VkCommandBuffer cmd, VkExtent2D extent) {
  VkViewport vp{0, 0, float(extent.width), float(extent.height), 0, 1};
  VkRect2D scissor{{0, 0}, extent};
  vkCmdSetViewport(cmd, 0, 1, &vp);
  vkCmdSetScissor(cmd, 0, 1, &scissor);
}

VkRenderingAttachmentInfo colour_attachment(const GpuImage& image, VkClearColorValue clear) {
  VkRenderingAttachmentInfo a{VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO};
  a.imageView = image.view();
  a.imageLayout = VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL;
  a.loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR;
  a.storeOp = VK_ATTACHMENT_STORE_OP_STORE;
  a.clearValue.color = clear;
  return a;
}

}  // namespace

struct FluidRenderer::Impl {
  Impl(VulkanContext& c, const SceneDescription& s, const RenderSettings& r)
      : ctx(c), scene(s), settings(r), formats(choose_formats(c)),
        targets(c, formats, {r.width, r.height}, {std::max(1u, r.width / 2), std::max(1u, r.height / 2)}),
        timer(c) {}
  ~Impl();

  VulkanContext& ctx;
  SceneDescription scene;
  RenderSettings settings;
  TargetFormats formats;
  RenderTargets targets;
  GpuTimer timer;
  SceneGeometry geometry;

  HostBuffer uniforms, scene_vertices, fluid_particles, sphere_particles, readback, tile_buffer;
  size_t fluid_capacity = 0;
  uint32_t fluid_count = 0, sphere_count = 0;
  std::vector<BodyPose> body_poses;
  std::vector<glm::vec3> fluid_cpu;  // for the tile classification
  TileGrid grid{};
  std::vector<uint8_t> tile_marks;
  std::vector<uint32_t> tiles;

  VkSampler sampler = VK_NULL_HANDLE;
  VkDescriptorPool pool = VK_NULL_HANDLE;
  VkDescriptorSetLayout graphics_set_layout = VK_NULL_HANDLE, filter_set_layout = VK_NULL_HANDLE,
                        composite_set_layout = VK_NULL_HANDLE;
  VkPipelineLayout scene_layout = VK_NULL_HANDLE, spheres_layout = VK_NULL_HANDLE, splat_layout = VK_NULL_HANDLE,
                   filter_layout = VK_NULL_HANDLE, composite_layout = VK_NULL_HANDLE;
  VkPipeline scene_pipeline = VK_NULL_HANDLE, spheres_pipeline = VK_NULL_HANDLE, splat_pipeline = VK_NULL_HANDLE,
             filter_pipeline = VK_NULL_HANDLE, composite_pipeline = VK_NULL_HANDLE;
  VkDescriptorSet graphics_set = VK_NULL_HANDLE;
  VkDescriptorSet filter_sets[3] = {};     // splat->a, a->b, b->a
  VkDescriptorSet composite_sets[3] = {};  // smoothed = splat (0 iterations), a, b
  VkCommandBuffer cmd = VK_NULL_HANDLE;
  VkFence fence = VK_NULL_HANDLE;
  bool frame_pending = false;

  float splat_radius() const { return float(scene.particle_radius_m) * settings.splat_radius_scale; }

  void create_buffers();
  void create_descriptors();
  void create_pipelines();
  void write_uniforms(const OrbitCamera& camera);
  void classify_tiles(const OrbitCamera& camera, CompositeMode mode);
  void record(VkCommandBuffer cmd, const OrbitCamera& camera, CompositeMode mode);
  void record_scene(VkCommandBuffer cmd, const glm::mat4& view);
  void record_splat(VkCommandBuffer cmd);
  const GpuImage& record_filter(VkCommandBuffer cmd);
  void record_composite(VkCommandBuffer cmd, CompositeMode mode);
  void ensure_capacity(HostBuffer& buffer, size_t bytes, VkBufferUsageFlags usage);
  void ensure_fluid_capacity(size_t particles);
  void write_particle_binding();
  void submit_and_wait();
};

FluidRenderer::Impl::~Impl() {
  VkDevice d = ctx.device();
  vkDeviceWaitIdle(d);
  for (VkPipeline p : {scene_pipeline, spheres_pipeline, splat_pipeline, filter_pipeline, composite_pipeline})
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

void FluidRenderer::Impl::ensure_capacity(HostBuffer& buffer, size_t bytes, VkBufferUsageFlags usage) {
  if (buffer.size() >= bytes && buffer.buffer()) return;
  if (frame_pending) submit_and_wait();
  vkQueueWaitIdle(ctx.queue());  // the old buffer may still be read by a windowed frame
  buffer = HostBuffer(ctx, std::max<size_t>(bytes + bytes / 2, 256), usage);
}

void FluidRenderer::Impl::ensure_fluid_capacity(size_t particles) {
  if (particles <= fluid_capacity && fluid_particles.buffer()) return;
  fluid_capacity = std::max<size_t>(particles + particles / 2, 1024);
  ensure_capacity(fluid_particles, fluid_capacity * sizeof(glm::vec3), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT);
  write_particle_binding();
}

void FluidRenderer::Impl::write_particle_binding() {
  VkDescriptorBufferInfo info{fluid_particles.buffer(), 0, VK_WHOLE_SIZE};
  VkWriteDescriptorSet w{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
  w.dstSet = graphics_set;
  w.dstBinding = 1;
  w.descriptorCount = 1;
  w.descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
  w.pBufferInfo = &info;
  vkUpdateDescriptorSets(ctx.device(), 1, &w, 0, nullptr);
}

void FluidRenderer::Impl::create_buffers() {
  uniforms = HostBuffer(ctx, sizeof(FrameUniforms), VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT);
  geometry = build_scene_geometry(scene);
  scene_vertices = HostBuffer(ctx, std::max<size_t>(geometry.vertices.size() * sizeof(SceneVertex), 64),
                              VK_BUFFER_USAGE_VERTEX_BUFFER_BIT);
  std::memcpy(scene_vertices.mapped(), geometry.vertices.data(), geometry.vertices.size() * sizeof(SceneVertex));
  ensure_capacity(sphere_particles, 1024 * sizeof(glm::vec4), VK_BUFFER_USAGE_VERTEX_BUFFER_BIT);
  readback = HostBuffer(ctx, VkDeviceSize(settings.width) * settings.height * 4, VK_BUFFER_USAGE_TRANSFER_DST_BIT);
  grid = {targets.half.width, targets.half.height};
  tile_buffer = HostBuffer(ctx, VkDeviceSize(grid.tiles_x()) * grid.tiles_y() * sizeof(uint32_t),
                           VK_BUFFER_USAGE_STORAGE_BUFFER_BIT);
  tile_marks.reserve(size_t(grid.tiles_x()) * grid.tiles_y());
  tiles.reserve(size_t(grid.tiles_x()) * grid.tiles_y());

  VkCommandBufferAllocateInfo alloc{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
  alloc.commandPool = ctx.command_pool();
  alloc.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
  alloc.commandBufferCount = 1;
  vk_check(vkAllocateCommandBuffers(ctx.device(), &alloc, &cmd), "vkAllocateCommandBuffers");
  VkFenceCreateInfo fence_info{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
  vk_check(vkCreateFence(ctx.device(), &fence_info, nullptr, &fence), "vkCreateFence");
}

void FluidRenderer::Impl::create_descriptors() {
  VkDevice d = ctx.device();
  VkSamplerCreateInfo s{VK_STRUCTURE_TYPE_SAMPLER_CREATE_INFO};
  s.magFilter = s.minFilter = VK_FILTER_LINEAR;  // the fig. 5 filter relies on bilinear averaging
  s.mipmapMode = VK_SAMPLER_MIPMAP_MODE_NEAREST;
  s.addressModeU = s.addressModeV = s.addressModeW = VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE;
  s.maxLod = 0.0f;
  vk_check(vkCreateSampler(d, &s, nullptr, &sampler), "vkCreateSampler");

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
                                             binding(6, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, cs)});

  VkDescriptorPoolSize sizes[] = {{VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, 7},
                                  {VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 15},
                                  {VK_DESCRIPTOR_TYPE_STORAGE_IMAGE, 6},
                                  {VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 7}};
  VkDescriptorPoolCreateInfo p{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
  p.maxSets = 7;
  p.poolSizeCount = 4;
  p.pPoolSizes = sizes;
  vk_check(vkCreateDescriptorPool(d, &p, nullptr, &pool), "vkCreateDescriptorPool");
  auto allocate = [&](VkDescriptorSetLayout layout) {
    VkDescriptorSetAllocateInfo a{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
    a.descriptorPool = pool;
    a.descriptorSetCount = 1;
    a.pSetLayouts = &layout;
    VkDescriptorSet set;
    vk_check(vkAllocateDescriptorSets(d, &a, &set), "vkAllocateDescriptorSets");
    return set;
  };

  // Every binding of every set is written: lavapipe 22.3 crashes in its worker thread on a bound
  // set with an unwritten binding, and the validation layer does not report it.
  VkDescriptorBufferInfo ubo{uniforms.buffer(), 0, sizeof(FrameUniforms)};
  auto write_ubo = [&](VkDescriptorSet set) {
    VkWriteDescriptorSet w{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
    w.dstSet = set;
    w.dstBinding = 0;
    w.descriptorCount = 1;
    w.descriptorType = VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER;
    w.pBufferInfo = &ubo;
    vkUpdateDescriptorSets(d, 1, &w, 0, nullptr);
  };
  VkDescriptorBufferInfo tile_info{tile_buffer.buffer(), 0, VK_WHOLE_SIZE};
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
  composite_pipeline = make_compute_pipeline(d, HAPFLUID_SHADER(composite_comp), composite_layout);
}

void FluidRenderer::Impl::write_uniforms(const OrbitCamera& camera) {
  const float w = float(settings.width), h = float(settings.height);
  const float hw = float(targets.half.width), hh = float(targets.half.height);
  FrameUniforms u{};
  u.view = camera.view();
  u.proj = camera.projection(w / h);
  // A light from above, behind the viewer's left shoulder.
  const glm::vec3 light_world = glm::normalize(camera.eye_m() - camera.target_m + glm::vec3(0, 0, 1.5f * camera.distance_m) +
                                               glm::vec3(-0.3f * camera.distance_m, 0, 0));
  u.light_dir_view = glm::vec4(glm::normalize(glm::mat3(u.view) * light_world), 0.0f);
  u.viewport = {w, h, 1.0f / w, 1.0f / h};
  u.half_viewport = {hw, hh, 1.0f / hw, 1.0f / hh};
  const float r = splat_radius();
  u.splat = {r, settings.filter_sigma_scale * r, no_fluid_depth_m, no_fluid_threshold_depth_m};
  const FluidLook& look = scene.look;
  u.fluid_colour = glm::vec4(look.colour, 1.0f);
  u.extinction = glm::vec4(look.extinction_per_m, 0.0f);
  u.specular = glm::vec4(look.specular, look.specular_exponent);
  u.refraction = {look.refraction_uv_per_m, u.proj[0][0], u.proj[1][1], 0.0f};
  u.floor_params = {float(geometry.checker_size_m), 0, 0, 0};
  std::memcpy(uniforms.mapped(), &u, sizeof u);
}

void FluidRenderer::Impl::classify_tiles(const OrbitCamera& camera, CompositeMode mode) {
  if (mode != CompositeMode::fluid) {
    all_tiles(grid, tiles);  // debug views paint pixels without fluid black
  } else if (settings.debug_spheres) {
    tiles.clear();  // no fluid surface: the output is the scene with its spheres
  } else {
    find_fluid_tiles(fluid_cpu, splat_radius(), camera.view(),
                     camera.projection(float(settings.width) / float(settings.height)), camera.near_m, grid, tile_marks,
                     tiles);
  }
  std::memcpy(tile_buffer.mapped(), tiles.data(), tiles.size() * sizeof(uint32_t));
}

void FluidRenderer::Impl::record_scene(VkCommandBuffer cmd, const glm::mat4&) {
  transition(cmd, targets.scene_colour, state::undefined, state::colour_target);
  transition(cmd, targets.scene_depth, state::undefined, state::colour_target);
  transition(cmd, targets.zbuffer, state::undefined, state::depth_target);
  const glm::vec3 bg = settings.background;
  VkRenderingAttachmentInfo colour[2] = {colour_attachment(targets.scene_colour, {{bg.r, bg.g, bg.b, 1.0f}}),
                                         colour_attachment(targets.scene_depth, {{no_fluid_depth_m, 0, 0, 0}})};
  VkRenderingAttachmentInfo depth{VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO};
  depth.imageView = targets.zbuffer.view();
  depth.imageLayout = VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL;
  depth.loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR;
  depth.storeOp = VK_ATTACHMENT_STORE_OP_DONT_CARE;
  depth.clearValue.depthStencil = {1.0f, 0};
  VkRenderingInfo info{VK_STRUCTURE_TYPE_RENDERING_INFO};
  info.renderArea = {{0, 0}, targets.full};
  info.layerCount = 1;
  info.colorAttachmentCount = 2;
  info.pColorAttachments = colour;
  info.pDepthAttachment = &depth;
  vkCmdBeginRendering(cmd, &info);
  set_viewport(cmd, targets.full);

  vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, scene_pipeline);
  vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, scene_layout, 0, 1, &graphics_set, 0, nullptr);
  VkDeviceSize offset = 0;
  VkBuffer vb = scene_vertices.buffer();
  vkCmdBindVertexBuffers(cmd, 0, 1, &vb, &offset);
  for (const DrawRange& range : geometry.draws) {
    ScenePush push{glm::mat4(1.0f), glm::vec4(range.colour, 1.0f), glm::vec4(range.checker_size_m, 0, 0, 0)};
    if (range.body >= 0 && size_t(range.body) < body_poses.size()) {
      const BodyPose& pose = body_poses[size_t(range.body)];
      push.model = glm::translate(glm::mat4(1.0f), pose.position_m) * glm::mat4_cast(pose.orientation) *
                   glm::scale(glm::mat4(1.0f), glm::vec3(float(range.scale)));
    } else if (range.body >= 0) {
      continue;  // no pose for this body in the frame: not drawn
    }
    vkCmdPushConstants(cmd, scene_layout, VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT, 0, sizeof push,
                       &push);
    vkCmdDraw(cmd, range.vertex_count, 1, range.first_vertex, 0);
  }
  if (settings.debug_spheres && sphere_count > 0) {
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, spheres_pipeline);
    vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, spheres_layout, 0, 1, &graphics_set, 0, nullptr);
    glm::vec4 radius{float(scene.particle_radius_m), 0, 0, 0};
    vkCmdPushConstants(cmd, spheres_layout, VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT, 0,
                       sizeof radius, &radius);
    VkBuffer pb = sphere_particles.buffer();
    vkCmdBindVertexBuffers(cmd, 0, 1, &pb, &offset);
    vkCmdDraw(cmd, 4, sphere_count, 0, 0);
  }
  vkCmdEndRendering(cmd);
  transition(cmd, targets.scene_colour, state::colour_target, state::compute_read);
  transition(cmd, targets.scene_depth, state::colour_target, state::compute_read);
}

void FluidRenderer::Impl::record_splat(VkCommandBuffer cmd) {
  transition(cmd, targets.splat, state::undefined, state::colour_target);
  VkRenderingAttachmentInfo colour = colour_attachment(targets.splat, {{no_fluid_depth_m, no_fluid_depth_m, 0, 0}});
  VkRenderingInfo info{VK_STRUCTURE_TYPE_RENDERING_INFO};
  info.renderArea = {{0, 0}, targets.half};
  info.layerCount = 1;
  info.colorAttachmentCount = 1;
  info.pColorAttachments = &colour;
  vkCmdBeginRendering(cmd, &info);
  const uint32_t instances = settings.debug_spheres ? 0 : fluid_count;
  if (instances > 0) {
    set_viewport(cmd, targets.half);
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, splat_pipeline);
    vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, splat_layout, 0, 1, &graphics_set, 0, nullptr);
    vkCmdDraw(cmd, 3 * instances, 1, 0, 0);  // one triangle per particle (splat.vert)
  }
  vkCmdEndRendering(cmd);
  transition(cmd, targets.splat, state::colour_target, state::compute_read);
}

const GpuImage& FluidRenderer::Impl::record_filter(VkCommandBuffer cmd) {
  if (settings.filter_iterations <= 0) return targets.splat;
  // Texels outside the dispatched tiles must read as "no fluid" to the next pass.
  const VkClearColorValue no_fluid{{no_fluid_depth_m, no_fluid_depth_m, no_fluid_depth_m, no_fluid_depth_m}};
  const VkImageSubresourceRange all{VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
  for (const GpuImage* image : {&targets.smoothed_a, &targets.smoothed_b}) {
    transition(cmd, *image, state::undefined, state::transfer_dst);
    vkCmdClearColorImage(cmd, image->image(), VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, &no_fluid, 1, &all);
    transition(cmd, *image, state::transfer_dst, state::compute_read);
  }
  vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, filter_pipeline);
  const GpuImage* destination = nullptr;
  for (int i = 0; i < settings.filter_iterations; ++i) {
    // splat -> a, then a -> b, b -> a, a -> b, ...
    const int set = i == 0 ? 0 : (i % 2 == 1 ? 1 : 2);
    destination = (i % 2 == 0) ? &targets.smoothed_a : &targets.smoothed_b;
    transition(cmd, *destination, state::compute_read, state::compute_write);
    vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, filter_layout, 0, 1, &filter_sets[set], 0, nullptr);
    if (!tiles.empty()) vkCmdDispatch(cmd, uint32_t(tiles.size()), 1, 1);
    transition(cmd, *destination, state::compute_write, state::compute_read);
  }
  return *destination;
}

void FluidRenderer::Impl::record_composite(VkCommandBuffer cmd, CompositeMode mode) {
  const int iterations = settings.filter_iterations;
  const int set = iterations <= 0 ? 0 : (iterations % 2 == 1 ? 1 : 2);
  // Pixels outside the fluid tiles are the scene (§5.2: T = 0 copies the scene colour).
  transition(cmd, targets.scene_colour, state::compute_read, state::transfer_src);
  transition(cmd, targets.output, state::undefined, state::transfer_dst);
  VkImageCopy copy{};
  copy.srcSubresource = copy.dstSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
  copy.extent = {targets.full.width, targets.full.height, 1};
  vkCmdCopyImage(cmd, targets.scene_colour.image(), VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, targets.output.image(),
                 VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 1, &copy);
  transition(cmd, targets.scene_colour, state::transfer_src, state::compute_read);
  transition(cmd, targets.output, state::transfer_dst, state::compute_write);
  vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, composite_pipeline);
  vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, composite_layout, 0, 1, &composite_sets[set], 0,
                          nullptr);
  CompositePush push{int32_t(mode), settings.thickness_view_max_m};
  vkCmdPushConstants(cmd, composite_layout, VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof push, &push);
  if (!tiles.empty()) vkCmdDispatch(cmd, uint32_t(tiles.size()), 1, 1);
  transition(cmd, targets.output, state::compute_write, state::transfer_src);
}

void FluidRenderer::Impl::record(VkCommandBuffer c, const OrbitCamera& camera, CompositeMode mode) {
  write_uniforms(camera);
  classify_tiles(camera, mode);
  timer.begin(c);
  record_scene(c, camera.view());
  timer.stamp(c);
  record_splat(c);
  timer.stamp(c);
  record_filter(c);
  timer.stamp(c);
  record_composite(c, mode);
  timer.stamp(c);
}

void FluidRenderer::Impl::submit_and_wait() {
  VkSubmitInfo submit{VK_STRUCTURE_TYPE_SUBMIT_INFO};
  submit.commandBufferCount = 1;
  submit.pCommandBuffers = &cmd;
  vk_check(vkQueueSubmit(ctx.queue(), 1, &submit, fence), "vkQueueSubmit (frame)");
  vk_check(vkWaitForFences(ctx.device(), 1, &fence, VK_TRUE, UINT64_MAX), "vkWaitForFences (frame)");
  vk_check(vkResetFences(ctx.device(), 1, &fence), "vkResetFences");
  frame_pending = false;
}

FluidRenderer::FluidRenderer(VulkanContext& ctx, const SceneDescription& scene, const RenderSettings& settings)
    : impl_(std::make_unique<Impl>(ctx, scene, settings)) {
  if (settings.width < 16 || settings.height < 16 || settings.width > 8192 || settings.height > 8192 ||
      settings.width % 2 || settings.height % 2)
    throw std::runtime_error("render: output size " + std::to_string(settings.width) + "x" +
                             std::to_string(settings.height) +
                             " must be even and 16..8192 pixels on each side (fluid buffers are half of it)");
  if (settings.filter_iterations < 0 || settings.filter_iterations > 64)
    throw std::runtime_error("render: filter iterations must be 0..64");
  if (!(scene.particle_radius_m > 0)) throw std::runtime_error("render: the particle radius must be > 0 m");
  impl_->create_buffers();
  impl_->create_descriptors();
  impl_->create_pipelines();
  camera_.target_m = scene.look_at_m;
  camera_.distance_m = float(scene.view_distance_m);
}

FluidRenderer::~FluidRenderer() = default;

void FluidRenderer::set_frame(const Frame& frame) {
  Impl& m = *impl_;
  m.body_poses = frame.body_poses;
  m.fluid_cpu.assign(frame.fluid_m.begin(), frame.fluid_m.end());
  m.fluid_count = uint32_t(frame.fluid_m.size());
  m.ensure_fluid_capacity(frame.fluid_m.size());
  std::memcpy(m.fluid_particles.mapped(), frame.fluid_m.data(), frame.fluid_m.size() * sizeof(glm::vec3));
  m.sphere_count = 0;
  if (m.settings.debug_spheres) {
    const size_t n = frame.fluid_m.size() + frame.solid_m.size();
    m.ensure_capacity(m.sphere_particles, n * sizeof(glm::vec4), VK_BUFFER_USAGE_VERTEX_BUFFER_BIT);
    auto* out = static_cast<glm::vec4*>(m.sphere_particles.mapped());
    for (const auto& p : frame.fluid_m) out[m.sphere_count++] = glm::vec4(p, 0.0f);
    for (const auto& p : frame.solid_m) out[m.sphere_count++] = glm::vec4(p, 1.0f);
  }
}

void FluidRenderer::record(VkCommandBuffer cmd, CompositeMode mode) { impl_->record(cmd, camera_, mode); }
VkImage FluidRenderer::output_image() const { return impl_->targets.output.image(); }
VkExtent2D FluidRenderer::output_extent() const { return impl_->targets.full; }
float FluidRenderer::no_fluid_threshold_m() const { return no_fluid_threshold_depth_m; }
float FluidRenderer::splat_radius_m() const { return impl_->splat_radius(); }

Rgba8Image FluidRenderer::render_to_image(CompositeMode mode) {
  Impl& m = *impl_;
  vk_check(vkResetCommandBuffer(m.cmd, 0), "vkResetCommandBuffer");
  VkCommandBufferBeginInfo begin{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
  begin.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
  vk_check(vkBeginCommandBuffer(m.cmd, &begin), "vkBeginCommandBuffer");
  m.record(m.cmd, camera_, mode);
  VkBufferImageCopy copy{};
  copy.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
  copy.imageExtent = {m.targets.full.width, m.targets.full.height, 1};
  vkCmdCopyImageToBuffer(m.cmd, m.targets.output.image(), VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, m.readback.buffer(), 1,
                         &copy);
  m.timer.stamp(m.cmd);
  vk_check(vkEndCommandBuffer(m.cmd), "vkEndCommandBuffer");
  m.frame_pending = true;
  m.submit_and_wait();
  Rgba8Image image{m.targets.full.width, m.targets.full.height, {}};
  const auto* bytes = static_cast<const uint8_t*>(m.readback.mapped());
  image.rgba.assign(bytes, bytes + size_t(image.width) * image.height * 4);
  return image;
}

FloatImage FluidRenderer::read_buffer(FluidBuffer which) {
  Impl& m = *impl_;
  const int iterations = m.settings.filter_iterations;
  const GpuImage& image = which != FluidBuffer::smoothed_front_depth ? m.targets.splat
                          : iterations <= 0                          ? m.targets.splat
                          : iterations % 2 == 1                      ? m.targets.smoothed_a
                                                                     : m.targets.smoothed_b;
  const bool two_channels = image.format() == m.formats.splat;
  const size_t texel_bytes = two_channels ? 8 : 4;
  if (image.format() == VK_FORMAT_R16G16_SFLOAT || image.format() == VK_FORMAT_R16_SFLOAT)
    throw std::runtime_error("render: read_buffer supports 32-bit fluid buffers only");
  const VkExtent2D e = image.extent();
  HostBuffer staging(m.ctx, VkDeviceSize(e.width) * e.height * texel_bytes, VK_BUFFER_USAGE_TRANSFER_DST_BIT);
  m.ctx.run_once([&](VkCommandBuffer c) {
    transition(c, image, state::compute_read, state::transfer_src);
    VkBufferImageCopy copy{};
    copy.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
    copy.imageExtent = {e.width, e.height, 1};
    vkCmdCopyImageToBuffer(c, image.image(), VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, staging.buffer(), 1, &copy);
    transition(c, image, state::transfer_src, state::compute_read);
  });
  FloatImage out{e.width, e.height, std::vector<float>(size_t(e.width) * e.height)};
  const auto* f = static_cast<const float*>(staging.mapped());
  for (size_t i = 0; i < out.values.size(); ++i) {
    if (!two_channels) out.values[i] = f[i];
    else if (which == FluidBuffer::back_depth) out.values[i] = -f[2 * i + 1];
    else out.values[i] = f[2 * i];
  }
  return out;
}

PassTimes FluidRenderer::pass_times() const {
  std::array<double, GpuTimer::capacity - 1> ms{};
  uint32_t n = 0;
  PassTimes t;
  if (!impl_->timer.intervals_ms(ms, n) || n < 4) return t;
  t.valid = true;
  t.scene_ms = ms[0];
  t.splat_ms = ms[1];
  t.filter_ms = ms[2];
  t.composite_ms = ms[3];
  t.copy_out_ms = n > 4 ? ms[4] : 0.0;
  for (uint32_t i = 0; i < n; ++i) t.total_ms += ms[i];
  return t;
}

std::string FluidRenderer::describe() const {
  return std::string(impl_->ctx.properties().deviceName) + "; " + impl_->formats.summary;
}

}  // namespace hapfluid::render
