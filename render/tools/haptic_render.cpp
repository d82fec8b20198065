// haptic-render: draws the fluid (§5 of the paper) in its own process so that drawing never
// stalls the simulation or the 1 kHz loop. See `haptic-render --help`.
#include <signal.h>

#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <memory>
#include <stdexcept>
#include <string>

#include "hapfluid/config/errors.hpp"
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

const char* usage = R"(usage: haptic-render [mode] [source] [options]
modes:
  (default)              a GLFW window: drag = orbit, wheel = zoom, Esc = quit
  --headless --out DIR   PNG frames DIR/frame_NNNNNN.png (and DIR/frames.mp4 when ffmpeg exists)
sources:
  --replay RUN_DIR       a recorded run of `haptic-sim --out RUN_DIR` (VTK frames + bodies.csv)
  --scene FILE           the run's scene file (default: RUN_DIR/scene.toml)
  --kind-field NAME      point array with the particle kind (default "kind"; 0 = fluid)
  --look NAME            override the scene's fluid look: water, batter, honey or syrup
  --synthetic ball|pool  a fixed particle set (no simulator): a ball of fluid, or a pool
  --particles N          synthetic pool: number of particles (default 32768)
  --live --scene FILE    the running haptic-sim's particles channel (shared memory), drawn as it
                         comes; waits for the simulator and follows its restarts
  --shm-prefix NAME      live: the rig's rt.shm.prefix (default "hapfluid")
  --max-force N          live: force shown as a full bar, newtons (default 10)
options:
  --frames N             stop after N frames          --duration S   stop after S seconds
  --width W --height H   output size (default 1024x768; fluid buffers are half of it)
  --filter-iterations N  bilateral filter passes (default 4, §5.1)
  --spheres              plain particle spheres instead of the fluid (debugging)
  --dump-buffers         also write depth, smoothed depth, thickness and normals images
  --camera-distance M --camera-yaw DEG --camera-pitch DEG
  --no-mp4               never run ffmpeg
  --screenshot FILE      windowed, with --frames: save the last presented image (overlay included)
  --timings              print the GPU time of every pass of every frame
  --validation           enable VK_LAYER_KHRONOS_validation; exit 3 if it reports anything
)";

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

[[noreturn]] void bad(const std::string& message) {
  std::fprintf(stderr, "haptic-render: %s\n(see haptic-render --help)\n", message.c_str());
  std::exit(2);
}

double number(const char* option, const char* text, double lo, double hi) {
  char* end = nullptr;
  double v = std::strtod(text, &end);
  if (end == text || *end || !(v >= lo && v <= hi))
    bad(std::string(option) + " " + text + ": must be a number in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
  return v;
}

Args parse(int argc, char** argv) {
  Args a;
  for (int i = 1; i < argc; ++i) {
    const std::string o = argv[i];
    auto value = [&]() -> const char* {
      if (i + 1 >= argc) bad(o + " needs a value");
      return argv[++i];
    };
    if (o == "--help" || o == "-h") { std::fputs(usage, stdout); std::exit(0); }
    else if (o == "--headless") a.headless = true;
    else if (o == "--out") a.out = value();
    else if (o == "--replay") a.replay = value();
    else if (o == "--scene") a.scene = value();
    else if (o == "--kind-field") a.kind_field = value();
    else if (o == "--look") a.look = value();
    else if (o == "--synthetic") a.synthetic = value();
    else if (o == "--live") a.live = true;
    else if (o == "--shm-prefix") a.shm_prefix = value();
    else if (o == "--max-force") a.max_force_n = number("--max-force", value(), 1e-3, 1e4);
    else if (o == "--particles") a.particles = long(number("--particles", value(), 1, 4e6));
    else if (o == "--frames") a.frames = long(number("--frames", value(), 1, 1e9));
    else if (o == "--duration") a.duration = number("--duration", value(), 0, 1e7);
    else if (o == "--width") a.settings.width = uint32_t(number("--width", value(), 16, 8192));
    else if (o == "--height") a.settings.height = uint32_t(number("--height", value(), 16, 8192));
    else if (o == "--filter-iterations") a.settings.filter_iterations = int(number("--filter-iterations", value(), 0, 64));
    else if (o == "--spheres") a.spheres = true;
    else if (o == "--dump-buffers") a.dump = true;
    else if (o == "--camera-distance") a.camera.distance_m = float(number("--camera-distance", value(), 0.05, 1000));
    else if (o == "--camera-yaw") a.camera.yaw_deg = float(number("--camera-yaw", value(), -360, 360));
    else if (o == "--camera-pitch") a.camera.pitch_deg = float(number("--camera-pitch", value(), -89, 89));
    else if (o == "--no-mp4") a.mp4 = false;
    else if (o == "--screenshot") a.screenshot = value();
    else if (o == "--timings") a.timings = true;
    else if (o == "--validation") a.validation = true;
    else bad("unknown option " + o);
  }
  a.settings.debug_spheres = a.spheres;
  if (a.headless && a.out.empty()) bad("--headless needs --out DIR");
  if (!a.screenshot.empty() && (a.headless || a.frames < 0)) bad("--screenshot needs the windowed mode and --frames N");
  if (!a.replay.empty() && !a.synthetic.empty()) bad("give either --replay or --synthetic, not both");
  if (!a.look.empty() && a.look != "water" && a.look != "batter" && a.look != "honey" && a.look != "syrup")
    bad("--look " + a.look + ": must be water, batter, honey or syrup");
  if (!a.synthetic.empty() && a.synthetic != "ball" && a.synthetic != "pool")
    bad("--synthetic " + a.synthetic + ": must be \"ball\" or \"pool\"");
  return a;
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
  const std::string text((std::istreambuf_iterator<char>(stats)), std::istreambuf_iterator<char>());
  const std::string key = "\"scene\": \"";
  const size_t at = text.find(key);
  if (at == std::string::npos) return {};
  const size_t end = text.find('"', at + key.size());
  if (end == std::string::npos) return {};
  const std::filesystem::path scene = text.substr(at + key.size(), end - at - key.size());
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
  const Args a = parse(argc, argv);
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
      std::fprintf(stderr, "haptic-render: the validation layer reported %d messages\n", summary.validation_messages);
      return 3;
    }
    return 0;
  } catch (const config::ConfigError& e) {
    std::fprintf(stderr, "haptic-render: %s\n", e.what());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "haptic-render: %s\n", e.what());
  }
  return 1;
}
