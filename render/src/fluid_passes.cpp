#include <cstring>

#include <glm/gtc/matrix_transform.hpp>

#include "fluid_renderer_impl.hpp"
#include "frame_uniforms.hpp"

namespace hapfluid::render {
namespace {

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

void FluidRenderer::Impl::cull_and_classify(const OrbitCamera& camera, CompositeMode mode) {
  // The visible particles go straight into the GPU buffer the splat pass reads (the GPU is not
  // using it: the previous frame has completed).
  auto* visible = static_cast<glm::vec3*>(fluid_particles.mapped());
  fluid_count = uint32_t(find_fluid_tiles(fluid_cpu, splat_radius(), camera.view(),
                                          camera.projection(float(settings.width) / float(settings.height)),
                                          camera.near_m, grid, tile_marks, tiles, visible));
  if (mode != CompositeMode::fluid) all_tiles(grid, tiles);  // debug views paint pixels without fluid black
  if (settings.debug_spheres) fluid_count = 0, tiles.clear();  // the output is the scene with its spheres
  std::memcpy(tile_buffer.mapped(), tiles.data(), tiles.size() * sizeof(uint32_t));
}

void FluidRenderer::Impl::record_scene(VkCommandBuffer cmd, const OrbitCamera& camera) {
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
  VkBuffer vb = scene_vertices.handle();
  vkCmdBindVertexBuffers(cmd, 0, 1, &vb, &offset);
  const glm::vec3 eye = camera.eye_m();
  for (const DrawRange& range : geometry.draws) {
    if (range.wall && glm::dot(range.wall_inward_normal, eye - range.wall_point_m) <= 0.0f) continue;  // in front
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
    VkBuffer pb = sphere_particles.handle();
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
  const uint32_t instances = fluid_count;  // visible splats (cull_and_classify)
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

const GpuImage& FluidRenderer::Impl::final_smoothed() const {
  const int iterations = settings.filter_iterations;
  return iterations <= 0 ? targets.splat : iterations % 2 == 1 ? targets.smoothed_a : targets.smoothed_b;
}

void FluidRenderer::Impl::record_normals(VkCommandBuffer cmd) {
  transition(cmd, targets.normals, state::undefined, state::compute_write);
  vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, normals_pipeline);
  vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, filter_layout, 0, 1, &normals_set, 0, nullptr);
  if (!tiles.empty()) vkCmdDispatch(cmd, uint32_t(tiles.size()), 1, 1);
  transition(cmd, targets.normals, state::compute_write, state::compute_read);
}

void FluidRenderer::Impl::record_composite(VkCommandBuffer cmd, CompositeMode mode) {
  const int iterations = settings.filter_iterations;
  const int set = iterations <= 0 ? 0 : (iterations % 2 == 1 ? 1 : 2);  // the set reading final_smoothed()
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
  cull_and_classify(camera, mode);
  timer.begin(c);
  record_scene(c, camera);
  timer.stamp(c);
  record_splat(c);
  timer.stamp(c);
  record_filter(c);
  timer.stamp(c);
  record_normals(c);
  timer.stamp(c);
  record_composite(c, mode);
  timer.stamp(c);
}

void FluidRenderer::Impl::submit_and_wait() {
  VkSubmitInfo submit{VK_STRUCTURE_TYPE_SUBMIT_INFO};
  submit.commandBufferCount = 1;
  submit.pCommandBuffers = &cmd;
  vk::check(vkQueueSubmit(ctx.queue(), 1, &submit, fence), "vkQueueSubmit (frame)");
  vk::check(vkWaitForFences(ctx.device(), 1, &fence, VK_TRUE, UINT64_MAX), "vkWaitForFences (frame)");
  vk::check(vkResetFences(ctx.device(), 1, &fence), "vkResetFences");
}

}  // namespace hapfluid::render
