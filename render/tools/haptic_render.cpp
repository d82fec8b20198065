// haptic-render: draws the fluid (§5 of the paper) in its own process so that drawing never
// stalls the simulation or the 1 kHz loop. See `haptic-render --help`.
#include <signal.h>

#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <memory>
#include <stdexcept>
#include <string>

#include "hapfluid/config/command_line.hpp"
#include "hapfluid/config/errors.hpp"
#include "hapfluid/config/json_output.hpp"
#include "hapfluid/config/log.hpp"
#include "hapfluid/config/scene.hpp"
#include "hapfluid/render/apps.hpp"
#include "hapfluid/render/replay_source.hpp"
#include "hapfluid/render/scene_description.hpp"
#include "hapfluid/render/shm_source.hpp"
#include "hapfluid/render/synthetic_source.hpp"

using namespace hapfluid;
using namespace hapfluid::render;

namespace {

std::atomic<bool> g_stop{false};
void on_stop_signal(int) { g_stop.store(true); }

struct Args {
  bool headless = false, spheres = false, dump = false, mp4 = true, timings = false, validation = false;
  std::string out, replay, scene, kind_field = "kind", synthetic, screenshot, look, shm_prefix = "hapfluid";
  bool live = false;
  double max_force_n = 10.0;
  long frames = -1, particles = 32768;
  double duration = -1;
  RenderSettings settings;
  CameraOverrides camera;
};

// A command line that cannot run: one line naming what is wrong, exit 2.
[[noreturn]] void bad(const std::string& message) {
  log::error("%s (haptic-render --help for usage)", message.c_str());
  std::exit(config::kUsageExitCode);
}

// Returns -1 to go on with `a`, else the exit code (help or version printed, a usage error said).
int parse(int argc, char** argv, Args& a) {
  CLI::App app{"Draws the fluid (paper section 5) in its own process. Modes: a GLFW window (default; drag = orbit, "
               "wheel = zoom, Esc = quit) or --headless PNG frames. Sources: --replay, --synthetic or --live.",
               "haptic-render"};
  config::apply_convention(app);
  app.add_flag("--headless", a.headless, "PNG frames DIR/frame_NNNNNN.png (and DIR/frames.mp4 when ffmpeg exists)");
  app.add_option("--out", a.out, "headless: the frame folder");
  app.add_option("--replay", a.replay, "a recorded run of `haptic-sim --out RUN_DIR` (VTK frames + bodies.csv)");
  app.add_option("--scene", a.scene, "the run's scene file (default: RUN_DIR/scene.toml)");
  app.add_option("--kind-field", a.kind_field, "point array with the particle kind (0 = fluid)")->capture_default_str();
  app.add_option("--look", a.look, "override the scene's fluid look")->check(CLI::IsMember({"water", "batter", "honey", "syrup"}));
  app.add_option("--synthetic", a.synthetic, "a fixed particle set (no simulator): a ball of fluid, or a pool")
      ->check(CLI::IsMember({"ball", "pool"}));
  app.add_option("--particles", a.particles, "synthetic pool: number of particles")->check(config::number_in(1, 4e6))
      ->capture_default_str();
  app.add_flag("--live", a.live, "the running haptic-sim's particles channel (shared memory), with --scene FILE; "
                                 "waits for the simulator and follows its restarts");
  app.add_option("--shm-prefix", a.shm_prefix, "live: the rig's rt.shm.prefix")->capture_default_str();
  app.add_option("--max-force", a.max_force_n, "live: force shown as a full bar, N")->check(config::number_in(1e-3, 1e4))
      ->capture_default_str();
  app.add_option("--frames", a.frames, "stop after N frames")->check(config::number_in(1, 1e9));
  app.add_option("--duration", a.duration, "stop after S seconds")->check(config::number_in(0, 1e7));
  app.add_option("--width", a.settings.width, "output width (fluid buffers are half of it)")->check(config::number_in(16, 8192))
      ->capture_default_str();
  app.add_option("--height", a.settings.height, "output height")->check(config::number_in(16, 8192))->capture_default_str();
  app.add_option("--filter-iterations", a.settings.filter_iterations, "bilateral filter passes (section 5.1)")
      ->check(config::number_in(0, 64))
      ->capture_default_str();
  app.add_flag("--spheres", a.spheres, "plain particle spheres instead of the fluid (debugging)");
  app.add_flag("--dump-buffers", a.dump, "also write depth, smoothed depth, thickness and normals images");
  float distance = 0, yaw = 0, pitch = 0;
  CLI::Option* distance_opt = app.add_option("--camera-distance", distance, "m")->check(config::number_in(0.05, 1000));
  CLI::Option* yaw_opt = app.add_option("--camera-yaw", yaw, "degrees")->check(config::number_in(-360, 360));
  CLI::Option* pitch_opt = app.add_option("--camera-pitch", pitch, "degrees")->check(config::number_in(-89, 89));
  bool no_mp4 = false;
  app.add_flag("--no-mp4", no_mp4, "never run ffmpeg");
  app.add_option("--screenshot", a.screenshot, "windowed, with --frames: save the last presented image (overlay included)");
  app.add_flag("--timings", a.timings, "print the GPU time of every pass of every frame");
  app.add_flag("--validation", a.validation, "enable VK_LAYER_KHRONOS_validation; exit 3 if it reports anything");
  if (const int code = config::parse_command_line(app, argc, argv); code >= 0) return code;
  a.mp4 = !no_mp4;
  if (distance_opt->count()) a.camera.distance_m = distance;
  if (yaw_opt->count()) a.camera.yaw_deg = yaw;
  if (pitch_opt->count()) a.camera.pitch_deg = pitch;
  a.settings.debug_spheres = a.spheres;
  if (a.headless && a.out.empty()) bad("--headless needs --out DIR");
  if (!a.screenshot.empty() && (a.headless || a.frames < 0)) bad("--screenshot needs the windowed mode and --frames N");
  if (!a.replay.empty() && !a.synthetic.empty()) bad("give either --replay or --synthetic, not both");
  return -1;
}

config::FluidLook look_named(const std::string& name) {
  if (name == "batter") return config::FluidLook::batter;
  if (name == "honey") return config::FluidLook::honey;
  if (name == "syrup") return config::FluidLook::syrup;
  return config::FluidLook::water;
}

// The scene a recorded run used: RUN/scene.toml, else the "scene" haptic-sim wrote into
// RUN/stats.json (relative to where haptic-sim ran, or to the run folder).
std::filesystem::path scene_of_run(const std::filesystem::path& run) {
  if (std::filesystem::exists(run / "scene.toml")) return run / "scene.toml";
  std::ifstream stats(run / "stats.json");
  if (!stats) return {};
  // A stats file that does not parse or names no scene is the same as none: the caller says
  // where it looked.
  const hapfluid::config::Json j = hapfluid::config::Json::parse(stats, nullptr, false);
  if (j.is_discarded() || !j.is_object() || !j.contains("scene") || !j["scene"].is_string()) return {};
  const std::filesystem::path scene = j["scene"].get<std::string>();
  if (scene.is_absolute() || std::filesystem::exists(scene)) return scene;
  return run / scene;
}

// The frame sources: live (the sim's particles channel), a recorded run, or a fixed particle set.
std::unique_ptr<FrameSource> make_source(const Args& a) {
  if (a.live) {
    if (a.scene.empty()) bad("--live needs --scene FILE (the scene the simulator runs: meshes, look, domain)");
    config::Scene scene = config::load_scene(a.scene);
    if (!a.look.empty()) scene.fluid.look = look_named(a.look);
    ShmSourceOptions options;
    options.prefix = a.shm_prefix;
    options.max_force_n = a.max_force_n;
    return std::make_unique<ShmSource>(describe_scene(scene), options);
  }
  if (!a.replay.empty()) {
    const std::filesystem::path scene_file = a.scene.empty() ? scene_of_run(a.replay) : std::filesystem::path(a.scene);
    if (scene_file.empty() || !std::filesystem::exists(scene_file))
      bad("cannot find the scene of the run " + a.replay + " (looked for --scene, " + a.replay + "/scene.toml and the "
          "\"scene\" of " + a.replay + "/stats.json): give --scene FILE, the scene the run used");
    config::Scene scene = config::load_scene(scene_file);
    if (!a.look.empty()) scene.fluid.look = look_named(a.look);
    return std::make_unique<ReplaySource>(a.replay, scene, a.kind_field);
  }
  if (!a.synthetic.empty()) {
    const bool ball = a.synthetic == "ball";
    const double radius = ball ? 0.01 : 0.008;
    Frame frame;
    frame.fluid_m = ball ? fluid_ball({0.0f, 0.0f, 0.15f}, 0.12, radius) : fluid_pool(uint32_t(a.particles), radius);
    SceneDescription scene = ball ? synthetic_scene(radius) : synthetic_pool_scene(radius);
    if (!a.look.empty()) scene.look = fluid_look(look_named(a.look));
    // A still scene repeats its frame; --frames/--duration bound it (default: one frame headless).
    const long frames = a.frames > 0 ? a.frames : (a.headless && a.duration < 0 ? 1 : 1000000000L);
    return std::make_unique<SyntheticSource>(scene, std::vector<Frame>{frame}, int(std::min(frames, 1000000000L)));
  }
  bad("no frame source: give --live --scene FILE, --replay RUN_DIR or --synthetic ball|pool");
}

}  // namespace

int main(int argc, char** argv) {
  Args a;
  if (const int code = parse(argc, argv, a); code >= 0) return code;
  // SIGINT/SIGTERM (Ctrl-C, the launcher, systemd) end the run like --duration: the PNG being
  // written is finished, not left as a .partial, and the summary and MP4 still come out.
  struct sigaction action {};
  action.sa_handler = on_stop_signal;
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
  try {
    auto source = make_source(a);
    RunSummary summary;
    if (a.headless) {
      HeadlessOptions h;
      h.out_dir = a.out;
      h.max_frames = a.frames;
      h.duration_s = a.duration;
      h.dump_buffers = a.dump;
      h.mp4 = a.mp4 && source->frame_count() > 1;
      h.print_timings = a.timings;
      h.settings = a.settings;
      h.camera = a.camera;
      h.validation = a.validation;
      h.stop_requested = &g_stop;
      summary = run_headless(*source, h);
    } else {
      WindowOptions w;
      w.max_frames = a.frames;
      w.duration_s = a.duration;
      w.settings = a.settings;
      w.camera = a.camera;
      w.validation = a.validation;
      w.screenshot = a.screenshot;
      w.stop_requested = &g_stop;
      summary = run_windowed(*source, w);
    }
    if (a.validation && summary.validation_messages > 0) {
      log::warning("the validation layer reported %d messages", summary.validation_messages);
      return 3;
    }
    return 0;
  } catch (const config::ConfigError& e) {
    log::error("%s", e.what());
  } catch (const std::exception& e) {
    log::error("%s", e.what());
  }
  return 1;
}
