// Windowed mode: the same FluidRenderer, its output image blitted to a GLFW window's swapchain
// image, statistics drawn on top. One frame in flight: the particle upload for the next frame
// waits for the previous one (the renderer's buffers are single).
#include <volk.h>
#define GLFW_INCLUDE_VULKAN
#include <GLFW/glfw3.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <stdexcept>

#include "hapfluid/config/log.hpp"
#include "hapfluid/render/apps.hpp"
#include "swapchain.hpp"
#include "text_overlay.hpp"
#include "vk_resources.hpp"

namespace hapfluid::render {
namespace {

struct Input {
  OrbitCamera* camera = nullptr;
  bool dragging = false;
  double last_x = 0, last_y = 0;
};

void on_mouse_button(GLFWwindow* w, int button, int action, int) {
  auto* in = static_cast<Input*>(glfwGetWindowUserPointer(w));
  if (button != GLFW_MOUSE_BUTTON_LEFT) return;
  in->dragging = action == GLFW_PRESS;
  glfwGetCursorPos(w, &in->last_x, &in->last_y);
}

void on_cursor(GLFWwindow* w, double x, double y) {
  auto* in = static_cast<Input*>(glfwGetWindowUserPointer(w));
  if (!in->dragging) return;
  in->camera->orbit(-0.005f * float(x - in->last_x), 0.005f * float(y - in->last_y));
  in->last_x = x, in->last_y = y;
}

void on_scroll(GLFWwindow* w, double, double dy) {
  static_cast<Input*>(glfwGetWindowUserPointer(w))->camera->zoom(dy > 0 ? 0.9f : 1.0f / 0.9f);
}

void on_key(GLFWwindow* w, int key, int, int action, int) {
  if (key == GLFW_KEY_ESCAPE && action == GLFW_PRESS) glfwSetWindowShouldClose(w, GLFW_TRUE);
}

struct GlfwSession {
  GlfwSession() {
    if (!glfwInit())
      throw std::runtime_error("GLFW: cannot initialise (no display? run under a desktop or xvfb-run, or use --headless)");
  }
  ~GlfwSession() { glfwTerminate(); }
};

void draw_stats(TextOverlay& overlay, const Frame& frame, double render_fps, double frames_per_s, const PassTimes& t) {
  overlay.clear();
  overlay.rectangle({8, 8}, {520, 150 + 30.0f * float(frame.device_forces.size())}, {0.0f, 0.0f, 0.0f, 0.55f});
  char line[160];
  std::snprintf(line, sizeof line, "render %.1f frames/s   GPU %.1f ms", render_fps, t.total_ms);
  overlay.text({18, 18}, line);
  std::snprintf(line, sizeof line, "  scene %.1f  splat %.1f  filter %.1f  normals %.1f  composite %.1f ms",
                t.scene_ms, t.splat_ms, t.filter_ms, t.normals_ms, t.composite_ms);
  overlay.text({18, 44}, line, {0.8f, 0.8f, 0.8f, 1.0f});
  if (frame.sim_steps_per_s > 0)
    std::snprintf(line, sizeof line, "sim %.0f steps/s   t = %.2f s", frame.sim_steps_per_s, frame.sim_time_s);
  else
    std::snprintf(line, sizeof line, "sim frames %.1f /s   t = %.2f s", frames_per_s, frame.sim_time_s);
  overlay.text({18, 72}, line);
  std::snprintf(line, sizeof line, "%zu fluid particles", frame.fluid_m.size());
  overlay.text({18, 100}, line);
  float y = 130;
  for (const DeviceForce& d : frame.device_forces) {
    const float fraction = std::clamp(d.force_n / std::max(d.max_force_n, 1e-6f), 0.0f, 1.0f);
    std::snprintf(line, sizeof line, "%s %.1f N", d.device.c_str(), d.force_n);
    overlay.text({18, y}, line);
    overlay.rectangle({200, y}, {420, y + 16}, {0.3f, 0.3f, 0.3f, 0.8f});
    overlay.rectangle({200, y}, {200 + 220 * fraction, y + 16},
                      fraction > 0.9f ? glm::vec4(0.9f, 0.2f, 0.1f, 1.0f) : glm::vec4(0.2f, 0.8f, 0.3f, 1.0f));
    y += 30;
  }
}

// The per-frame Vulkan objects of the window loop (one frame in flight).
struct FrameSync {
  explicit FrameSync(vk::Context& c) : ctx(c) {
    VkCommandBufferAllocateInfo alloc{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
    alloc.commandPool = ctx.command_pool();
    alloc.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
    alloc.commandBufferCount = 1;
    vk::check(vkAllocateCommandBuffers(ctx.device(), &alloc, &cmd), "vkAllocateCommandBuffers");
    VkFenceCreateInfo fence_info{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
    fence_info.flags = VK_FENCE_CREATE_SIGNALED_BIT;
    vk::check(vkCreateFence(ctx.device(), &fence_info, nullptr, &fence), "vkCreateFence");
    VkSemaphoreCreateInfo sem_info{VK_STRUCTURE_TYPE_SEMAPHORE_CREATE_INFO};
    vk::check(vkCreateSemaphore(ctx.device(), &sem_info, nullptr, &acquired), "vkCreateSemaphore");
  }
  ~FrameSync() {
    vkDeviceWaitIdle(ctx.device());
    vkDestroySemaphore(ctx.device(), acquired, nullptr);
    vkDestroyFence(ctx.device(), fence, nullptr);
    vkFreeCommandBuffers(ctx.device(), ctx.command_pool(), 1, &cmd);
  }
  void wait() { vk::check(vkWaitForFences(ctx.device(), 1, &fence, VK_TRUE, UINT64_MAX), "vkWaitForFences"); }

  vk::Context& ctx;
  VkCommandBuffer cmd = VK_NULL_HANDLE;
  VkFence fence = VK_NULL_HANDLE;
  VkSemaphore acquired = VK_NULL_HANDLE;  // swapchain image ready to be written
};

// After the renderer's passes: its output scaled onto the swapchain image, the overlay on top,
// and (for --screenshot) a copy of exactly what is presented.
void record_presentation(VkCommandBuffer cmd, const FluidRenderer& renderer, const Swapchain& swapchain,
                         uint32_t index, TextOverlay& overlay, const vk::Buffer* screenshot) {
  const VkImage target = swapchain.image(index);
  transition(cmd, target, VK_IMAGE_ASPECT_COLOR_BIT, state::undefined, state::transfer_dst);
  const VkExtent2D src = renderer.output_extent(), dst = swapchain.extent();
  VkImageBlit blit{};
  blit.srcSubresource = blit.dstSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
  blit.srcOffsets[1] = {int32_t(src.width), int32_t(src.height), 1};
  blit.dstOffsets[1] = {int32_t(dst.width), int32_t(dst.height), 1};
  vkCmdBlitImage(cmd, renderer.output_image(), VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, target,
                 VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 1, &blit, VK_FILTER_LINEAR);
  transition(cmd, target, VK_IMAGE_ASPECT_COLOR_BIT, state::transfer_dst, state::colour_target);
  overlay.record(cmd, swapchain.view(index), dst);
  if (!screenshot) {
    transition(cmd, target, VK_IMAGE_ASPECT_COLOR_BIT, state::colour_target, state::present);
    return;
  }
  transition(cmd, target, VK_IMAGE_ASPECT_COLOR_BIT, state::colour_target, state::transfer_src);
  VkBufferImageCopy copy{};
  copy.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
  copy.imageExtent = {dst.width, dst.height, 1};
  vkCmdCopyImageToBuffer(cmd, target, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, screenshot->handle(), 1, &copy);
  transition(cmd, target, VK_IMAGE_ASPECT_COLOR_BIT, state::transfer_src, state::present);
}

// Submits `sync.cmd` (after the image is acquired) and presents; false when the swapchain must be
// recreated (window resized).
bool submit_and_present(vk::Context& ctx, FrameSync& sync, const Swapchain& swapchain, uint32_t index) {
  VkPipelineStageFlags wait_stage = VK_PIPELINE_STAGE_TRANSFER_BIT;
  VkSemaphore done = swapchain.render_done(index);
  VkSubmitInfo submit{VK_STRUCTURE_TYPE_SUBMIT_INFO};
  submit.waitSemaphoreCount = 1;
  submit.pWaitSemaphores = &sync.acquired;
  submit.pWaitDstStageMask = &wait_stage;
  submit.commandBufferCount = 1;
  submit.pCommandBuffers = &sync.cmd;
  submit.signalSemaphoreCount = 1;
  submit.pSignalSemaphores = &done;
  vk::check(vkQueueSubmit(ctx.queue(), 1, &submit, sync.fence), "vkQueueSubmit");
  VkPresentInfoKHR present{VK_STRUCTURE_TYPE_PRESENT_INFO_KHR};
  present.waitSemaphoreCount = 1;
  present.pWaitSemaphores = &done;
  present.swapchainCount = 1;
  VkSwapchainKHR handle = swapchain.handle();
  present.pSwapchains = &handle;
  present.pImageIndices = &index;
  const VkResult presented = vkQueuePresentKHR(ctx.queue(), &present);
  if (presented == VK_ERROR_OUT_OF_DATE_KHR || presented == VK_SUBOPTIMAL_KHR) return false;
  vk::check(presented, "vkQueuePresentKHR");
  return true;
}

void save_screenshot(const vk::Buffer& pixels, VkExtent2D extent, VkFormat format, const std::filesystem::path& file) {
  Rgba8Image image{extent.width, extent.height, {}};
  const auto* bytes = static_cast<const uint8_t*>(pixels.mapped());
  image.rgba.assign(bytes, bytes + size_t(image.width) * image.height * 4);
  if (format == VK_FORMAT_B8G8R8A8_UNORM)
    for (size_t i = 0; i < image.rgba.size(); i += 4) std::swap(image.rgba[i], image.rgba[i + 2]);
  write_png(file, image);
}

double seconds(std::chrono::steady_clock::duration d) { return std::chrono::duration<double>(d).count(); }

}  // namespace

RunSummary run_windowed(FrameSource& source, const WindowOptions& options) {
  GlfwSession glfw;
  if (!glfwVulkanSupported()) throw std::runtime_error("GLFW: no Vulkan loader found for the window");
  glfwWindowHint(GLFW_CLIENT_API, GLFW_NO_API);
  GLFWwindow* window = glfwCreateWindow(int(options.settings.width), int(options.settings.height),
                                        ("haptic-render: " + source.scene().name).c_str(), nullptr, nullptr);
  if (!window) throw std::runtime_error("GLFW: cannot create a window");
  uint32_t ext_count = 0;
  const char** ext = glfwGetRequiredInstanceExtensions(&ext_count);
  vk::ContextOptions ctx_options = context_options(options.validation, true);
  for (uint32_t i = 0; i < ext_count; ++i) ctx_options.instance_extensions.emplace_back(ext[i]);

  RunSummary summary;
  {
    vk::Context ctx(ctx_options);
    VkSurfaceKHR surface;
    vk::check(glfwCreateWindowSurface(ctx.instance(), window, nullptr, &surface), "glfwCreateWindowSurface");
    {
      FluidRenderer renderer(ctx, source.scene(), options.settings);
      OrbitCamera camera = renderer.camera();
      options.camera.apply(camera);
      Input input{&camera};
      glfwSetWindowUserPointer(window, &input);
      glfwSetMouseButtonCallback(window, on_mouse_button);
      glfwSetCursorPosCallback(window, on_cursor);
      glfwSetScrollCallback(window, on_scroll);
      glfwSetKeyCallback(window, on_key);
      Swapchain swapchain(ctx, surface, window);
      TextOverlay overlay(ctx, swapchain.format());
      log::info("window on %s", renderer.describe().c_str());

      FrameSync sync(ctx);
      vk::Buffer screenshot;
      Frame frame;
      bool have_frame = false;
      double first_sim_time_s = 0.0;
      double render_fps = 0, source_fps = 0;
      const auto start = std::chrono::steady_clock::now();
      auto last = start, last_source = start;
      while (!glfwWindowShouldClose(window)) {
        if (options.max_frames >= 0 && summary.frames >= options.max_frames) break;
        const auto now = std::chrono::steady_clock::now();
        if (options.duration_s >= 0 && seconds(now - start) >= options.duration_s) break;
        if (options.stop_requested && options.stop_requested->load()) break;
        glfwPollEvents();
        // The newest frame, never waiting for one: a finished replay keeps showing its last frame.
        // A recording (finite source) plays at its own pace: the next frame once its sim time is due.
        const bool due = !have_frame || source.frame_count() < 0 ||
                         frame.sim_time_s - first_sim_time_s <= seconds(now - start);
        const bool fresh = due && source.next_frame(frame) == FrameStatus::new_frame;
        if (fresh) {
          if (!have_frame) first_sim_time_s = frame.sim_time_s;
          const double dt = seconds(now - last_source);
          if (have_frame && dt > 0) source_fps = 0.9 * source_fps + 0.1 / dt;
          last_source = now;
          have_frame = true;
        }

        sync.wait();
        const PassTimes times = renderer.pass_times();
        uint32_t index = 0;
        const VkResult acquire =
            vkAcquireNextImageKHR(ctx.device(), swapchain.handle(), UINT64_MAX, sync.acquired, VK_NULL_HANDLE, &index);
        if (acquire == VK_ERROR_OUT_OF_DATE_KHR) {
          swapchain.recreate(window);
          continue;
        }
        if (acquire != VK_SUBOPTIMAL_KHR) vk::check(acquire, "vkAcquireNextImageKHR");
        vk::check(vkResetFences(ctx.device(), 1, &sync.fence), "vkResetFences");

        renderer.set_camera(camera);
        if (fresh) renderer.set_frame(frame);  // the GPU is done with the previous one (fence)
        draw_stats(overlay, frame, render_fps, source_fps, times);
        const bool last_frame = options.max_frames >= 0 && summary.frames + 1 == options.max_frames;
        const bool take_screenshot = last_frame && !options.screenshot.empty();
        if (take_screenshot)
          screenshot = vk::Buffer(ctx, VkDeviceSize(swapchain.extent().width) * swapchain.extent().height * 4,
                                  VK_BUFFER_USAGE_TRANSFER_DST_BIT, vk::MemoryUse::host);

        vk::check(vkResetCommandBuffer(sync.cmd, 0), "vkResetCommandBuffer");
        VkCommandBufferBeginInfo begin{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
        begin.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
        vk::check(vkBeginCommandBuffer(sync.cmd, &begin), "vkBeginCommandBuffer");
        renderer.record(sync.cmd);
        record_presentation(sync.cmd, renderer, swapchain, index, overlay, take_screenshot ? &screenshot : nullptr);
        vk::check(vkEndCommandBuffer(sync.cmd), "vkEndCommandBuffer");
        const VkExtent2D presented_extent = swapchain.extent();  // before a possible recreation
        if (!submit_and_present(ctx, sync, swapchain, index)) {
          sync.wait();
          swapchain.recreate(window);
        }
        if (take_screenshot) {
          sync.wait();
          save_screenshot(screenshot, presented_extent, swapchain.format(), options.screenshot);
        }

        ++summary.frames;
        const auto after = std::chrono::steady_clock::now();
        const double dt = seconds(after - last);
        last = after;
        if (dt > 0) render_fps = render_fps == 0 ? 1.0 / dt : 0.9 * render_fps + 0.1 / dt;
        summary.mean_frame_ms += times.total_ms;
      }
      if (summary.frames) summary.mean_frame_ms /= double(summary.frames);
      log::info("presented %ld frames (%.1f frames/s at the end)", summary.frames, render_fps);
    }
    vkDestroySurfaceKHR(ctx.instance(), surface, nullptr);
    ctx.destroy_device();  // count what the validation layer says about leaks too
    summary.validation_messages = int(ctx.validation_counts().errors + ctx.validation_counts().warnings);
  }
  glfwDestroyWindow(window);
  return summary;
}

}  // namespace hapfluid::render
