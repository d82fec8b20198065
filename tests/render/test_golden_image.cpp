// The whole §5 pipeline against a reviewed reference image: a ball of water in front of the
// checkered floor, 400 x 300, water look. Tolerance PSNR >= 35 dB (a different CPU's vector width
// may change the last bit of a few pixels; a broken pass changes thousands).
// Regenerate after an intended change with HAPFLUID_UPDATE_GOLDEN=1, then look at the image.
#include <cstdlib>

#include "render_fixture.hpp"

using namespace hapfluid::render;
using namespace hapfluid::render::test;

TEST_F(ValidatedRenderTest, BallOfWaterMatchesTheGoldenImage) {
  RenderSettings s;
  s.width = 400;
  s.height = 300;
  FluidRenderer renderer(*ctx, ball_scene(), s);
  OrbitCamera camera = close_camera(renderer);
  camera.distance_m = 0.45f;
  renderer.set_camera(camera);
  renderer.set_frame(ball_frame());
  const Rgba8Image image = renderer.render_to_image();
  const std::filesystem::path golden = std::filesystem::path(HAPFLUID_SOURCE_DIR) / "tests/render/golden/ball_water.png";
  const std::filesystem::path actual = std::filesystem::path(HAPFLUID_BINARY_DIR) / "tests/render_ball_water_actual.png";
  const char* update = std::getenv("HAPFLUID_UPDATE_GOLDEN");
  if (update && *update == '1') {
    write_png(golden, image);
    GTEST_SKIP() << "golden image rewritten: " << golden;
  }
  write_png(actual, image);  // for a look when the comparison fails
  const Rgba8Image expected = read_png(golden);
  ASSERT_EQ(expected.width, image.width);
  ASSERT_EQ(expected.height, image.height);
  EXPECT_GE(psnr_db(image, expected), 35.0) << "compare " << actual << " with " << golden;
}
