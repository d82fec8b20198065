#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <thread>

#include "hapfluid/config/log.hpp"
#include "hapfluid/render/apps.hpp"

namespace hapfluid::render {
namespace {

std::string numbered(const char* prefix, uint64_t index, const char* suffix) {
  char name[96];
  std::snprintf(name, sizeof name, "%s%06llu%s", prefix, static_cast<unsigned long long>(index), suffix);
  return name;
}

bool ffmpeg_available() { return std::system("command -v ffmpeg >/dev/null 2>&1") == 0; }

void dump_buffers(FluidRenderer& renderer, const std::filesystem::path& dir, uint64_t index) {
  const float threshold = renderer.no_fluid_threshold_m();
  write_png(dir / numbered("frame_", index, "_depth.png"),
            depth_to_grey(renderer.read_buffer(FluidBuffer::raw_front_depth), threshold));
  write_png(dir / numbered("frame_", index, "_smoothed_depth.png"),
            depth_to_grey(renderer.read_buffer(FluidBuffer::smoothed_front_depth), threshold));
  write_png(dir / numbered("frame_", index, "_thickness.png"), renderer.render_to_image(CompositeMode::thickness));
  write_png(dir / numbered("frame_", index, "_normals.png"), renderer.render_to_image(CompositeMode::normals));
}

}  // namespace

void CameraOverrides::apply(OrbitCamera& camera) const {
  constexpr float deg = 3.14159265f / 180.0f;
  if (distance_m) camera.distance_m = *distance_m;
  if (yaw_deg) camera.yaw_rad = *yaw_deg * deg;
  if (pitch_deg) camera.pitch_rad = *pitch_deg * deg;
}

RunSummary run_headless(FrameSource& source, const HeadlessOptions& options) {
  std::filesystem::create_directories(options.out_dir);
  const auto buffers_dir = options.out_dir / "buffers";
  if (options.dump_buffers) std::filesystem::create_directories(buffers_dir);

  vk::Context ctx(context_options(options.validation, false));
  RunSummary summary;
  double gpu_ms_sum = 0.0;
  {
    FluidRenderer renderer(ctx, source.scene(), options.settings);
    OrbitCamera camera = renderer.camera();
    options.camera.apply(camera);
    renderer.set_camera(camera);
    log::info("headless on %s", renderer.describe().c_str());

    const auto start = std::chrono::steady_clock::now();
    Frame frame;
    while (options.max_frames < 0 || summary.frames < options.max_frames) {
      const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      if (options.duration_s >= 0 && elapsed >= options.duration_s) break;
      if (options.stop_requested && options.stop_requested->load()) break;
      const FrameStatus status = source.next_frame(frame);
      if (status == FrameStatus::end_of_stream) break;
      if (status == FrameStatus::unchanged) {  // a live source with nothing new yet
        std::this_thread::sleep_for(std::chrono::milliseconds(2));
        continue;
      }
      renderer.set_frame(frame);
      Rgba8Image image = renderer.render_to_image();
      const PassTimes t = renderer.pass_times();
      gpu_ms_sum += t.total_ms;
      if (options.print_timings && t.valid)
        log::info("frame %llu: %zu fluid particles, %.1f ms (scene %.1f, splat %.1f, filter %.1f, "
                  "normals %.1f, composite %.1f, read-back %.1f)",
                  static_cast<unsigned long long>(frame.index), frame.fluid_m.size(), t.total_ms, t.scene_ms,
                  t.splat_ms, t.filter_ms, t.normals_ms, t.composite_ms, t.copy_out_ms);
      write_png(options.out_dir / numbered("frame_", uint64_t(summary.frames), ".png"), image);
      if (options.dump_buffers) dump_buffers(renderer, buffers_dir, uint64_t(summary.frames));
      ++summary.frames;
    }
  }
  ctx.destroy_device();  // count what the validation layer says about leaks too
  summary.mean_frame_ms = summary.frames ? gpu_ms_sum / double(summary.frames) : 0.0;
  summary.validation_messages = int(ctx.validation_counts().errors + ctx.validation_counts().warnings);
  log::info("wrote %ld frames to %s (mean %.1f ms per frame)", summary.frames,
            options.out_dir.string().c_str(), summary.mean_frame_ms);

  if (options.mp4 && summary.frames > 0) {
    if (!ffmpeg_available()) {
      log::notice("ffmpeg not found: skipping the MP4 (the PNG frames are in %s)",
                  options.out_dir.string().c_str());
    } else {
      const auto mp4 = options.out_dir / "frames.mp4";
      const std::string command = "ffmpeg -loglevel error -y -framerate " + std::to_string(options.mp4_frame_rate_hz) +
                                  " -i '" + (options.out_dir / "frame_%06d.png").string() +
                                  "' -pix_fmt yuv420p -vf 'pad=ceil(iw/2)*2:ceil(ih/2)*2' '" + mp4.string() + "'";
      if (std::system(command.c_str()) != 0)
        log::warning("ffmpeg failed; the PNG frames are in %s", options.out_dir.string().c_str());
      else
        log::info("wrote %s", mp4.string().c_str());
    }
  }
  return summary;
}

}  // namespace hapfluid::render
