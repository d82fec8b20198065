// Scenes the simulator cannot run must fail before stepping, with a message naming the body and
// the fix (a user editing a scene file must not have to read the code).
#include <gtest/gtest.h>

#include "hapfluid/config/errors.hpp"
#include "test_support.hpp"

using namespace hapfluid::sim;
namespace config = hapfluid::config;

namespace {

std::string error_of(const std::string& toml, const std::map<std::string, config::TriangleMesh>& meshes) {
  const auto dir = test::temp_dir("bad");
  try {
    const auto scene = test::write_scene(dir, toml, meshes);
    build_model(scene);
  } catch (const config::ConfigError& e) {
    std::filesystem::remove_all(dir);
    return e.what();
  } catch (const std::exception& e) {
    std::filesystem::remove_all(dir);
    return e.what();
  }
  std::filesystem::remove_all(dir);
  return "";
}

const char* kBase = R"(
name = "bad"
[domain]
min_m = [0.0, 0.0, 0.0]
max_m = [0.3, 0.3, 0.3]
[fluid]
particle_spacing_m = 0.01
speed_of_sound_m_s = 10.0
)";

}  // namespace

TEST(BadScenes, BodyOverlappingAWallIsRefused) {
  const std::string e = error_of(std::string(kBase) + R"(
[[bodies]]
name = "crate"
mesh = "box.obj"
position_m = [0.001, 0.1, 0.1]
density_kg_m3 = 500.0
)", {{"box.obj", test::box_mesh(0.1, 0.1, 0.1)}});
  EXPECT_NE(e.find("bodies.crate: the body overlaps the domain wall x_min"), std::string::npos) << e;
}

TEST(BadScenes, SamplingSpacingTooCoarseToHoldFluidIsRefused) {
  const std::string e = error_of(std::string(kBase) + R"(
[[bodies]]
name = "crate"
mesh = "box.obj"
position_m = [0.1, 0.1, 0.1]
density_kg_m3 = 500.0
sampling_spacing_m = 0.03
)", {{"box.obj", test::box_mesh(0.1, 0.1, 0.1)}});
  EXPECT_NE(e.find("bodies.crate: sampling spacing 0.03 m is larger than the support radius"), std::string::npos) << e;
}

TEST(BadScenes, OpenMeshIsRefused) {
  auto open = test::box_mesh(0.1, 0.1, 0.1);
  open.triangles.resize(10);
  const std::string e = error_of(std::string(kBase) + R"(
[[bodies]]
name = "lidless"
mesh = "open.obj"
position_m = [0.1, 0.1, 0.1]
density_kg_m3 = 500.0
)", {{"open.obj", open}});
  EXPECT_NE(e.find("bodies.lidless"), std::string::npos) << e;
  EXPECT_NE(e.find("not closed"), std::string::npos) << e;
}

TEST(BadScenes, NonFiniteValueIsRefusedByKey) {
  const std::string e = error_of(std::string(kBase) + "[[fluid.blocks]]\nmin_m = [0.0, 0.0, nan]\nmax_m = [0.1, 0.1, 0.1]\n", {});
  EXPECT_NE(e.find("min_m"), std::string::npos) << e;
}
