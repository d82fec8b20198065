// Fuzz target: a scene file as a user writes it, through parse_scene (which also reads and places
// the meshes its bodies name) and the scripted hand motion every batch run and the fake device
// evaluate from it. Bad input must be a ConfigError naming the file; any other exception escaping
// is a bug.
//
// The scene is read as <scratch>/scenes/fuzz.toml, and <scratch>/meshes/ holds, under the name of
// every shipped mesh, the box of that mesh's bounds: a shipped scene validates exactly as it does
// in config/scenes/ (validation looks at a mesh's bounds only), while each input parses 8 vertices
// instead of hundreds. The mesh readers have their own targets (mesh_obj, mesh_stl).
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

#include "config_errors.hpp"
#include "fuzz_target.h"
#include "hapfluid/config/mesh.hpp"
#include "hapfluid/config/motion.hpp"
#include "hapfluid/config/scene.hpp"

using namespace hapfluid;
namespace fs = std::filesystem;

namespace {

struct Scratch {
  fs::path root = fs::temp_directory_path() / ("hapfluid-fuzz-scene-" + std::to_string(::getpid()));
  fs::path scene = root / "scenes" / "fuzz.toml";

  Scratch() {
    fs::create_directories(root / "scenes");
    fs::create_directories(root / "meshes");
    for (const auto& entry : fs::directory_iterator(fs::path(HAPFLUID_SOURCE_DIR) / "config" / "meshes")) {
      const config::Aabb b = config::mesh_bounds(config::load_mesh(entry.path()));
      std::ofstream box(root / "meshes" / entry.path().filename());
      box.precision(17);
      for (int corner = 0; corner < 8; ++corner)
        box << "v " << (corner & 1 ? b.max_m.x : b.min_m.x) << ' ' << (corner & 2 ? b.max_m.y : b.min_m.y) << ' '
            << (corner & 4 ? b.max_m.z : b.min_m.z) << '\n';
      box << "f 1 3 4 2\nf 5 6 8 7\nf 1 2 6 5\nf 3 7 8 4\nf 1 5 7 3\nf 2 4 8 6\n";
      if (!box) {
        std::perror(root.c_str());
        std::exit(1);
      }
    }
  }
  ~Scratch() {
    std::error_code ignored;
    fs::remove_all(root, ignored);
  }
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const Scratch scratch;
  try {
    const config::Scene scene =
        config::parse_scene(std::string(reinterpret_cast<const char*>(data), size), scratch.scene);
    ++hapfluid_fuzz_accepted;
    for (const config::SceneDevice& device : scene.devices) {
      std::vector<double> times = {0.0, 0.5 * scene.duration_s, scene.duration_s};
      for (const config::MotionSegment& s : device.motion.segments) times.insert(times.end(), {s.start_s, s.stop_s});
      for (double t : times) (void)config::evaluate_motion(device.motion, t);
    }
  } catch (const config::ConfigError& error) {
    fuzz::check_config_error(error, scratch.scene);
  }
  return 0;
}
