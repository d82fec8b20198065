#include "hapfluid/render/fluid_renderer.hpp"

#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <string_view>

#include "fluid_renderer_impl.hpp"
#include "frame_uniforms.hpp"

namespace hapfluid::render {

vk::ContextOptions context_options(bool validation, bool swapchain) {
  vk::ContextOptions o;
  o.application = "haptic-render";
  o.queue = vk::QueueKind::graphics;
  // The renderer's own switch (its unit's environment): the simulator is not slowed by it.
  const char* env = std::getenv("HAPFLUID_VK_VALIDATION");
  o.validation = validation || (env && *env && std::string_view(env) != "0");
  o.swapchain = swapchain;
  return o;
}

FluidRenderer::FluidRenderer(vk::Context& ctx, const SceneDescription& scene, const RenderSettings& settings)
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
  m.ensure_fluid_capacity(frame.fluid_m.size());
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
  vk::check(vkResetCommandBuffer(m.cmd, 0), "vkResetCommandBuffer");
  VkCommandBufferBeginInfo begin{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
  begin.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
  vk::check(vkBeginCommandBuffer(m.cmd, &begin), "vkBeginCommandBuffer");
  m.record(m.cmd, camera_, mode);
  VkBufferImageCopy copy{};
  copy.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
  copy.imageExtent = {m.targets.full.width, m.targets.full.height, 1};
  vkCmdCopyImageToBuffer(m.cmd, m.targets.output.image(), VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, m.readback.handle(), 1,
                         &copy);
  m.timer.stamp(m.cmd);
  vk::check(vkEndCommandBuffer(m.cmd), "vkEndCommandBuffer");
  m.submit_and_wait();
  Rgba8Image image{m.targets.full.width, m.targets.full.height, {}};
  const auto* bytes = static_cast<const uint8_t*>(m.readback.mapped());
  image.rgba.assign(bytes, bytes + size_t(image.width) * image.height * 4);
  return image;
}

FloatImage FluidRenderer::read_buffer(FluidBuffer which) {
  Impl& m = *impl_;
  const GpuImage& image = which == FluidBuffer::smoothed_front_depth ? m.final_smoothed() : m.targets.splat;
  const bool two_channels = image.format() == m.formats.splat;
  const size_t texel_bytes = two_channels ? 8 : 4;
  if (image.format() == VK_FORMAT_R16G16_SFLOAT || image.format() == VK_FORMAT_R16_SFLOAT)
    throw std::runtime_error("render: read_buffer supports 32-bit fluid buffers only");
  const VkExtent2D e = image.extent();
  vk::Buffer staging(m.ctx, VkDeviceSize(e.width) * e.height * texel_bytes, VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                     vk::MemoryUse::host);
  m.ctx.run_once([&](VkCommandBuffer c) {
    transition(c, image, state::compute_read, state::transfer_src);
    VkBufferImageCopy copy{};
    copy.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
    copy.imageExtent = {e.width, e.height, 1};
    vkCmdCopyImageToBuffer(c, image.image(), VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, staging.handle(), 1, &copy);
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
  std::array<double, vk::GpuTimer::capacity - 1> ms{};
  uint32_t n = 0;
  PassTimes t;
  if (!impl_->timer.intervals_ms(ms, n) || n < 5) return t;
  t.valid = true;
  t.scene_ms = ms[0];
  t.splat_ms = ms[1];
  t.filter_ms = ms[2];
  t.normals_ms = ms[3];
  t.composite_ms = ms[4];
  t.copy_out_ms = n > 5 ? ms[5] : 0.0;
  for (uint32_t i = 0; i < n; ++i) t.total_ms += ms[i];
  return t;
}

std::string FluidRenderer::describe() const {
  return std::string(impl_->ctx.properties().deviceName) + "; " + impl_->formats.summary;
}

}  // namespace hapfluid::render