// Internals of FluidRenderer shared by its three source files:
//   fluid_renderer.cpp         the public API (frames in, images out)
//   fluid_renderer_setup.cpp   buffers, descriptor sets and pipelines, created once
//   fluid_passes.cpp           the passes of one frame, recorded into a command buffer
#pragma once

#include <vector>

#include "fluid_tiles.hpp"
#include "hapfluid/vk/gpu_timer.hpp"
#include "hapfluid/render/fluid_renderer.hpp"
#include "render_targets.hpp"
#include "scene_geometry.hpp"

namespace hapfluid::render {

struct ScenePush {
  glm::mat4 model;
  glm::vec4 colour;
  glm::vec4 params;
};
struct CompositePush {
  int32_t mode;
  float thickness_scale_m;
};

struct FluidRenderer::Impl {
  Impl(vk::Context& c, const SceneDescription& s, const RenderSettings& r)
      : ctx(c), scene(s), settings(r), formats(choose_formats(c)),
        targets(c, formats, {r.width, r.height}, {std::max(1u, r.width / 2), std::max(1u, r.height / 2)}),
        timer(c) {}
  ~Impl();

  vk::Context& ctx;
  SceneDescription scene;
  RenderSettings settings;
  TargetFormats formats;
  RenderTargets targets;
  vk::GpuTimer timer;
  SceneGeometry geometry;

  vk::Buffer uniforms, scene_vertices, fluid_particles, sphere_particles, readback, tile_buffer;
  size_t fluid_capacity = 0;
  uint32_t fluid_count = 0, sphere_count = 0;  // fluid: visible splats of this frame
  std::vector<BodyPose> body_poses;
  std::vector<glm::vec3> fluid_cpu;  // every fluid particle; culled per frame into fluid_particles
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
             filter_pipeline = VK_NULL_HANDLE, normals_pipeline = VK_NULL_HANDLE, composite_pipeline = VK_NULL_HANDLE;
  VkDescriptorSet graphics_set = VK_NULL_HANDLE;
  VkDescriptorSet filter_sets[3] = {};     // splat->a, a->b, b->a
  VkDescriptorSet normals_set = VK_NULL_HANDLE;  // final smoothed depth -> normals
  VkDescriptorSet composite_sets[3] = {};  // smoothed = splat (0 iterations), a, b
  VkCommandBuffer cmd = VK_NULL_HANDLE;
  VkFence fence = VK_NULL_HANDLE;

  float splat_radius() const { return float(scene.particle_radius_m) * settings.splat_radius_scale; }

  void create_buffers();
  void create_descriptors();
  void create_pipelines();
  void write_uniforms(const OrbitCamera& camera);
  void cull_and_classify(const OrbitCamera& camera, CompositeMode mode);
  void record(VkCommandBuffer cmd, const OrbitCamera& camera, CompositeMode mode);
  void record_scene(VkCommandBuffer cmd, const OrbitCamera& camera);
  void record_splat(VkCommandBuffer cmd);
  const GpuImage& record_filter(VkCommandBuffer cmd);
  void record_normals(VkCommandBuffer cmd);
  void record_composite(VkCommandBuffer cmd, CompositeMode mode);
  const GpuImage& final_smoothed() const;
  void ensure_capacity(vk::Buffer& buffer, size_t bytes, VkBufferUsageFlags usage);
  void ensure_fluid_capacity(size_t particles);
  void write_particle_binding();
  void submit_and_wait();
};


}  // namespace hapfluid::render
