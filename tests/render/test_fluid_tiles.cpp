// The CPU-side choice of screen tiles the filter and composite passes run on. It must be
// conservative (a tile with a fluid pixel is never skipped: the GPU test
// SmoothingNeverMixesFluidWithEmptyPixels checks that end to end) and tight enough to pay off.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "fluid_tiles.hpp"
#include "hapfluid/render/camera.hpp"

using namespace hapfluid::render;

namespace {

struct TileScene {
  OrbitCamera camera;
  TileGrid grid{512, 384};  // the half-resolution buffers of a 1024 x 768 frame
  glm::mat4 view, proj;
  TileScene() {
    camera.target_m = glm::vec3(0.0f);
    camera.distance_m = 1.0f;
    view = camera.view();
    proj = camera.projection(1024.0f / 768.0f);
  }
  std::vector<uint32_t> tiles_of(const std::vector<glm::vec3>& centres, float radius_m = 0.012f) {
    std::vector<uint8_t> scratch;
    std::vector<uint32_t> tiles;
    visible.assign(centres.size(), glm::vec3(0.0f));
    visible.resize(find_fluid_tiles(centres, radius_m, view, proj, camera.near_m, grid, scratch, tiles, visible.data()));
    return tiles;
  }
  std::vector<glm::vec3> visible;  // the splats the last tiles_of() call kept for drawing
};

}  // namespace

TEST(FluidTiles, OneSplatAtTheTargetMarksOnlyTheTilesAroundTheScreenCentre) {
  TileScene s;
  // A 12 mm splat 1 m away spans about 2 x 0.012 / 0.83 x 384 = 11 texels: at most 3 x 3 tiles.
  const auto tiles = s.tiles_of({glm::vec3(0.0f)});
  ASSERT_FALSE(tiles.empty());
  EXPECT_LE(tiles.size(), 9u);
  for (uint32_t t : tiles) {
    const int x = int(t & 0xffff), y = int(t >> 16);
    EXPECT_NEAR(x, 512 / 2 / 8, 1);
    EXPECT_NEAR(y, 384 / 2 / 8, 1);
  }
}

TEST(FluidTiles, ParticlesBehindTheCameraOrNotFiniteMarkNothing) {
  TileScene s;
  const glm::vec3 behind = 2.0f * s.camera.eye_m();  // on the far side of the eye from the target
  const float nan = std::numeric_limits<float>::quiet_NaN();
  EXPECT_TRUE(s.tiles_of({behind, glm::vec3(nan, 0.0f, 0.0f), glm::vec3(0.0f, INFINITY, 0.0f)}).empty());
}

TEST(FluidTiles, ASplatStraddlingTheScreenEdgeMarksTheEdgeTile) {
  TileScene s;
  // A point just outside the left edge whose splat still reaches in.
  const glm::mat4 inverse_view = glm::inverse(s.view);
  const float half_width_at_1m = 1.0f / s.proj[0][0];
  const glm::vec3 view_point(-half_width_at_1m - 0.005f, 0.0f, -1.0f);
  const glm::vec3 world = glm::vec3(inverse_view * glm::vec4(view_point, 1.0f));
  const auto tiles = s.tiles_of({world});
  ASSERT_FALSE(tiles.empty());
  for (uint32_t t : tiles) EXPECT_EQ(t & 0xffff, 0u);
  EXPECT_EQ(s.visible.size(), 1u) << "a splat that reaches into the picture is drawn";
}

TEST(FluidTiles, SplatsEntirelyOffScreenAreCulled) {
  TileScene s;
  const glm::mat4 inverse_view = glm::inverse(s.view);
  const float half_width_at_1m = 1.0f / s.proj[0][0];
  const glm::vec3 off_screen = glm::vec3(inverse_view * glm::vec4(-half_width_at_1m - 0.1f, 0.0f, -1.0f, 1.0f));
  const glm::vec3 on_screen = glm::vec3(inverse_view * glm::vec4(0.1f, 0.05f, -1.0f, 1.0f));
  s.tiles_of({off_screen, on_screen, off_screen});
  ASSERT_EQ(s.visible.size(), 1u);
  EXPECT_NEAR(glm::distance(s.visible[0], on_screen), 0.0f, 1e-6f);
}

TEST(FluidTiles, AllTilesCoverTheBufferIncludingPartialTiles) {
  std::vector<uint32_t> tiles;
  all_tiles(TileGrid{100, 50}, tiles);  // 13 x 7 tiles of 8 texels
  EXPECT_EQ(tiles.size(), 13u * 7u);
}
