// Fuzz target: a scene file as a user writes it, through parse_scene (which also reads and places
// the meshes its bodies name, relative to config/scenes/ like a shipped scene) and the scripted
// hand motion every batch run and the fake device evaluate from it. Bad input must be a
// ConfigError naming the file; any other exception escaping is a bug.
#include <cmath>
#include <string>
#include <vector>

#include "config_errors.hpp"
#include "fuzz_target.h"
#include "hapfluid/config/motion.hpp"
#include "hapfluid/config/scene.hpp"

using namespace hapfluid;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::filesystem::path file = std::filesystem::path(HAPFLUID_SOURCE_DIR) / "config/scenes/fuzz.toml";
  try {
    const config::Scene scene = config::parse_scene(std::string(reinterpret_cast<const char*>(data), size), file);
    ++hapfluid_fuzz_accepted;
    for (const config::SceneDevice& device : scene.devices) {
      std::vector<double> times = {0.0, 0.5 * scene.duration_s, scene.duration_s};
      for (const config::MotionSegment& s : device.motion.segments) times.insert(times.end(), {s.start_s, s.stop_s});
      for (double t : times) (void)config::evaluate_motion(device.motion, t);
    }
  } catch (const config::ConfigError& error) {
    fuzz::check_config_error(error, file);
  }
  return 0;
}
