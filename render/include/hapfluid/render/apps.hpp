// The two ways haptic-render runs a FrameSource: headless (PNG files, optional buffer dumps and
// MP4) and windowed (GLFW swapchain, orbit camera, on-screen statistics). Both drive the same
// FluidRenderer.
#pragma once

#include <atomic>
#include <filesystem>
#include <optional>

#include "hapfluid/render/fluid_renderer.hpp"

namespace hapfluid::render {

struct CameraOverrides {
  std::optional<float> distance_m, yaw_deg, pitch_deg;
  void apply(OrbitCamera& camera) const;
};

struct HeadlessOptions {
  std::filesystem::path out_dir;
  long max_frames = -1;          // -1: until the source ends (or the duration)
  double duration_s = -1.0;      // wall-clock limit, -1: none
  bool dump_buffers = false;     // depth, smoothed depth, thickness, normals per frame
  bool mp4 = true;               // when ffmpeg is installed
  bool print_timings = false;
  double mp4_frame_rate_hz = 30.0;
  RenderSettings settings;
  CameraOverrides camera;
  bool validation = false;
  // Set (e.g. by a SIGTERM handler) to finish the frame in hand and stop as if the duration had
  // ended: the frames written so far stay whole and the summary is still printed.
  const std::atomic<bool>* stop_requested = nullptr;
};

struct RunSummary {
  long frames = 0;
  double mean_frame_ms = 0.0;   // GPU time per frame (timestamp queries)
  int validation_messages = 0;
};

RunSummary run_headless(FrameSource& source, const HeadlessOptions& options);

struct WindowOptions {
  long max_frames = -1;          // close after this many presented frames (tests)
  double duration_s = -1.0;
  const std::atomic<bool>* stop_requested = nullptr;  // as in HeadlessOptions
  RenderSettings settings;
  CameraOverrides camera;
  bool validation = false;
  std::filesystem::path screenshot;  // with max_frames: the last presented image as PNG
};

RunSummary run_windowed(FrameSource& source, const WindowOptions& options);

}  // namespace hapfluid::render
