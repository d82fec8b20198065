// The screen-space fluid renderer of the paper's §5, one frame as a fixed sequence of passes:
//   1. scene      (full res)  floor + body meshes -> scene colour S_c and linear depth S_d
//   2. splat      (half res)  fluid particles as sphere splats, radius 1.2 x particle radius ->
//                             front depth and back depth in one pass (§5.1)
//   3. filter     (half res)  the fast 5-sample bilateral filter of fig. 5, N iterations (§5.1)
//   4. normals    (half res)  finite differences of the smoothed depth (§5.2)
//   5. composite  (full res)  equation 15 over the scene in one compute pass (§5.2)
// Headless and windowed modes share it: the result is an offscreen image that is either read back
// or blitted to a swapchain image.
#pragma once

#include <memory>
#include <string>

#include "hapfluid/render/camera.hpp"
#include "hapfluid/render/frame_source.hpp"
#include "hapfluid/render/image_io.hpp"
#include "hapfluid/vk/context.hpp"

namespace hapfluid::render {

// The Vulkan context the renderer needs: a graphics+compute queue on Vulkan 1.3 (dynamic
// rendering, synchronization2), with a swapchain for a window.
vk::ContextOptions context_options(bool validation, bool swapchain);

struct RenderSettings {
  uint32_t width = 1024, height = 768;  // output pixels; fluid buffers are half of it (§5.1)
  int filter_iterations = 4;            // §5.1: "we set the number of iterations to four"
  float splat_radius_scale = 1.2f;      // §5.1: splat radius = 1.2 x particle radius
  float filter_sigma_scale = 1.0f;      // bilateral range sigma, in splat radii
  bool debug_spheres = false;           // draw plain particle spheres instead of the fluid
  float thickness_view_max_m = 0.3f;    // CompositeMode::thickness shows this thickness as white
  glm::vec3 background{0.55f, 0.62f, 0.70f};
};

enum class CompositeMode : int32_t {
  fluid = 0,     // equation 15
  normals = 1,   // the finite-difference normals as colour (n * 0.5 + 0.5), black without fluid
  thickness = 2  // T(p) as grey up to RenderSettings::thickness_view_max_m, black without fluid
};

enum class FluidBuffer { raw_front_depth, back_depth, smoothed_front_depth };

// GPU time of each pass of the last completed frame (timestamp queries), in milliseconds.
struct PassTimes {
  bool valid = false;
  double scene_ms = 0, splat_ms = 0, filter_ms = 0, normals_ms = 0, composite_ms = 0, copy_out_ms = 0, total_ms = 0;
};

class FluidRenderer {
 public:
  FluidRenderer(vk::Context& ctx, const SceneDescription& scene, const RenderSettings& settings);
  ~FluidRenderer();
  FluidRenderer(const FluidRenderer&) = delete;
  FluidRenderer& operator=(const FluidRenderer&) = delete;

  void set_camera(const OrbitCamera& camera) { camera_ = camera; }
  const OrbitCamera& camera() const { return camera_; }
  // Keeps the frame's particles and body poses for the next record() (growing GPU buffers waits
  // for the GPU to go idle).
  void set_frame(const Frame& frame);

  // Culls the particles against the camera and writes the visible ones and the per-frame values
  // into GPU-visible memory, so the previous frame must have completed (headless: always;
  // windowed: after its fence). Then records every pass into `cmd`; the output image ends in
  // TRANSFER_SRC_OPTIMAL layout.
  void record(VkCommandBuffer cmd, CompositeMode mode = CompositeMode::fluid);
  VkImage output_image() const;
  VkExtent2D output_extent() const;

  // Headless: record, submit, wait, read back.
  Rgba8Image render_to_image(CompositeMode mode = CompositeMode::fluid);
  // After a render: one of the half-resolution fluid buffers, depths in metres. Pixels without
  // fluid hold a value above no_fluid_threshold_m().
  FloatImage read_buffer(FluidBuffer which);
  float no_fluid_threshold_m() const;
  float splat_radius_m() const;

  PassTimes pass_times() const;        // of the last submitted frame, once it completed
  std::string describe() const;        // device and the formats chosen at start-up

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  OrbitCamera camera_;
};

}  // namespace hapfluid::render
