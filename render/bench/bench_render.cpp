// bench_render: milliseconds per frame of the §5 pipeline for the paper's workload, 32,768 fluid
// particles (a 1 m pool) at 1024 x 768 with 4 filter iterations, and the split per pass from
// timestamp queries. Target on lavapipe with 2 cores: <= 66 ms (>= 15 frames/s).
//   bench_render --out out/bench/bench_render.json [--frames N]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "hapfluid/config/command_line.hpp"
#include "hapfluid/config/json_output.hpp"
#include "hapfluid/config/log.hpp"
#include "hapfluid/render/fluid_renderer.hpp"
#include "hapfluid/render/synthetic_source.hpp"

using namespace hapfluid::render;

namespace {

namespace log = hapfluid::log;

struct Case {
  uint32_t particles, width, height;
  int filter_iterations;
};

hapfluid::config::Json run_case(hapfluid::vk::Context& ctx, const Case& c, int frames) {
  const double radius = 0.008;
  RenderSettings s;
  s.width = c.width;
  s.height = c.height;
  s.filter_iterations = c.filter_iterations;
  FluidRenderer renderer(ctx, synthetic_pool_scene(radius), s);
  Frame frame;
  frame.fluid_m = fluid_pool(c.particles, radius);
  renderer.set_frame(frame);
  OrbitCamera camera = renderer.camera();
  for (int i = 0; i < 3; ++i) renderer.render_to_image();  // shader JIT and first-touch of memory
  std::vector<double> gpu, wall;
  PassTimes sum;
  for (int i = 0; i < frames; ++i) {
    camera.orbit(0.01f, 0.0f);  // a slowly orbiting camera, as in the windowed mode
    renderer.set_camera(camera);
    const auto t0 = std::chrono::steady_clock::now();
    renderer.render_to_image();
    wall.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    const PassTimes t = renderer.pass_times();
    gpu.push_back(t.total_ms);
    sum.scene_ms += t.scene_ms, sum.splat_ms += t.splat_ms, sum.filter_ms += t.filter_ms;
    sum.normals_ms += t.normals_ms, sum.composite_ms += t.composite_ms, sum.copy_out_ms += t.copy_out_ms;
  }
  auto mean = [](const std::vector<double>& v) {
    double s = 0;
    for (double x : v) s += x;
    return s / double(v.size());
  };
  std::vector<double> sorted = wall;
  std::sort(sorted.begin(), sorted.end());
  const double p95 = sorted[std::min(sorted.size() - 1, size_t(0.95 * double(sorted.size())))];
  // The fastest frame: what the pipeline costs when the shared machine leaves it alone.
  const double best = sorted.front();
  const double median = sorted[sorted.size() / 2];
  const double n = frames;
  const hapfluid::config::Json record = hapfluid::config::bench_record(
      "bench_render",
      {{"particles", c.particles}, {"width", c.width}, {"height", c.height}, {"filter_iterations", c.filter_iterations},
       {"fluid_buffer_scale", 0.5}, {"device", std::string(ctx.properties().deviceName)}},
      {{"ms_per_frame", mean(wall)}, {"frames_per_s", 1000.0 / mean(wall)}, {"p95_ms_per_frame", p95},
       {"min_ms_per_frame", best}, {"median_ms_per_frame", median}, {"gpu_ms_per_frame", mean(gpu)},
       {"scene_ms", sum.scene_ms / n}, {"splat_ms", sum.splat_ms / n}, {"filter_ms", sum.filter_ms / n},
       {"normals_ms", sum.normals_ms / n}, {"composite_ms", sum.composite_ms / n}, {"readback_ms", sum.copy_out_ms / n}});
  log::info("%u particles %ux%u, %d filter passes: %.1f ms/frame wall (%.1f frames/s, median %.1f, best %.1f), GPU %.1f ms = "
            "scene %.1f + splat %.1f + filter %.1f + normals %.1f + composite %.1f + read-back %.1f",
            c.particles, c.width, c.height, c.filter_iterations, mean(wall), 1000.0 / mean(wall), median, best, mean(gpu),
            sum.scene_ms / n, sum.splat_ms / n, sum.filter_ms / n, sum.normals_ms / n, sum.composite_ms / n,
            sum.copy_out_ms / n);
  return record;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Milliseconds per frame of the fluid renderer on the paper's workload; JSON records to --out.",
               "bench_render"};
  hapfluid::config::apply_convention(app);
  std::string out;
  int frames = 20;
  app.add_option("--out", out, "JSON records (a list) to this file (default: stdout)");
  app.add_option("--frames", frames, "frames timed per case")->check(CLI::Range(1, 100000));
  if (const int code = hapfluid::config::parse_command_line(app, argc, argv); code >= 0) return code;
  try {
    hapfluid::vk::Context ctx(context_options(false, false));
    std::vector<hapfluid::config::Json> records;
    records.push_back(run_case(ctx, {32768, 1024, 768, 4}, frames));  // the paper's workload
    records.push_back(run_case(ctx, {8192, 1024, 768, 4}, frames));
    if (out.empty())
      std::fputs(hapfluid::config::json_text(records).c_str(), stdout);
    else
      hapfluid::config::write_json_atomically(out, records);
    return 0;
  } catch (const std::exception& e) {
    log::error("%s", e.what());
    return 1;
  }
}
