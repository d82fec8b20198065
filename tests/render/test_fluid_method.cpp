// Checks of the §5 method itself on a ball of water: the bilateral filter smooths (fig. 5), the
// thickness follows the amount of fluid along the ray (eq. 15's T), and pixels without fluid are
// the scene, untouched. All with the validation layer on.
#include <cmath>

#include "render_fixture.hpp"

using namespace hapfluid::render;
using namespace hapfluid::render::test;

namespace {

RenderSettings small_settings(int filter_iterations = 4) {
  RenderSettings s;
  s.width = 640;
  s.height = 480;
  s.filter_iterations = filter_iterations;
  return s;
}

// Sum of the squared discrete Laplacian over pixels whose 4 neighbours are all fluid in `mask`:
// the high-frequency energy of a depth map (the "blobby" look of raw splats, §5.1).
double laplacian_energy(const FloatImage& depth, const FloatImage& mask, float threshold, int& samples) {
  double energy = 0;
  samples = 0;
  for (uint32_t y = 1; y + 1 < depth.height; ++y)
    for (uint32_t x = 1; x + 1 < depth.width; ++x) {
      const float c = mask.at(x, y), l = mask.at(x - 1, y), r = mask.at(x + 1, y), u = mask.at(x, y - 1),
                  d = mask.at(x, y + 1);
      if (c > threshold || l > threshold || r > threshold || u > threshold || d > threshold) continue;
      const double lap = 4.0 * depth.at(x, y) - depth.at(x - 1, y) - depth.at(x + 1, y) - depth.at(x, y - 1) -
                         depth.at(x, y + 1);
      energy += lap * lap;
      ++samples;
    }
  return energy;
}

}  // namespace

TEST_F(ValidatedRenderTest, SmoothedDepthHasLessHighFrequencyEnergyThanRawDepth) {
  FluidRenderer renderer(*ctx, ball_scene(), small_settings());
  renderer.set_camera(close_camera(renderer));
  renderer.set_frame(ball_frame());
  renderer.render_to_image();
  const FloatImage raw = renderer.read_buffer(FluidBuffer::raw_front_depth);
  const FloatImage smooth = renderer.read_buffer(FluidBuffer::smoothed_front_depth);
  int n_raw = 0, n_smooth = 0;
  const float t = renderer.no_fluid_threshold_m();
  const double e_raw = laplacian_energy(raw, raw, t, n_raw);
  const double e_smooth = laplacian_energy(smooth, raw, t, n_smooth);
  ASSERT_GT(n_raw, 1000) << "the ball must cover a good part of the half-resolution buffer";
  // Four iterations of the 17-tap filter must remove most of the splat bumps' curvature.
  EXPECT_LT(e_smooth, 0.5 * e_raw) << "raw " << e_raw << " smoothed " << e_smooth;
}

TEST_F(ValidatedRenderTest, SmoothingNeverMixesFluidWithEmptyPixels) {
  // Fig. 5: an outer sample is used only if its four depths are fluid. A filter that averaged in
  // the "no fluid" value would push silhouette depths metres away; one that grew the fluid would
  // paint it where no particle is.
  FluidRenderer renderer(*ctx, ball_scene(), small_settings());
  renderer.set_camera(close_camera(renderer));
  renderer.set_frame(ball_frame());
  renderer.render_to_image();
  const FloatImage raw = renderer.read_buffer(FluidBuffer::raw_front_depth);
  const FloatImage smooth = renderer.read_buffer(FluidBuffer::smoothed_front_depth);
  const float t = renderer.no_fluid_threshold_m();
  float lo = 1e9f, hi = -1e9f;
  for (float v : raw.values)
    if (v <= t) lo = std::min(lo, v), hi = std::max(hi, v);
  for (size_t i = 0; i < raw.values.size(); ++i) {
    ASSERT_EQ(raw.values[i] <= t, smooth.values[i] <= t) << "coverage changed at texel " << i;
    if (raw.values[i] <= t) {
      ASSERT_GE(smooth.values[i], lo - 1e-5f);
      ASSERT_LE(smooth.values[i], hi + 1e-5f);
    }
  }
}

TEST_F(ValidatedRenderTest, ZeroFilterIterationsCompositeTheRawDepth) {
  FluidRenderer renderer(*ctx, ball_scene(), small_settings(0));
  renderer.set_camera(close_camera(renderer));
  renderer.set_frame(ball_frame());
  renderer.render_to_image();
  const FloatImage raw = renderer.read_buffer(FluidBuffer::raw_front_depth);
  const FloatImage smooth = renderer.read_buffer(FluidBuffer::smoothed_front_depth);
  EXPECT_EQ(raw.values, smooth.values);
}

TEST_F(ValidatedRenderTest, ThicknessIsLargerWhereTheFluidIsDeeper) {
  // Through the centre of a ball of radius R the ray crosses about 2 (R + splat radius) of fluid;
  // at 0.75 R off-centre the chord is shorter (2 sqrt(R^2 - (0.75 R)^2) = 1.3 R for a solid ball).
  FluidRenderer renderer(*ctx, ball_scene(), small_settings());
  const OrbitCamera camera = close_camera(renderer);
  renderer.set_camera(camera);
  renderer.set_frame(ball_frame());
  renderer.render_to_image();
  const FloatImage front = renderer.read_buffer(FluidBuffer::raw_front_depth);
  const FloatImage back = renderer.read_buffer(FluidBuffer::back_depth);
  const glm::vec3 right = glm::normalize(glm::vec3(glm::inverse(camera.view())[0]));
  const glm::ivec2 centre = project(camera, ball_centre_m, front.width, front.height);
  const glm::ivec2 side = project(camera, ball_centre_m + right * float(0.75 * ball_radius_m), front.width, front.height);
  const float t_centre = back.at(centre.x, centre.y) - front.at(centre.x, centre.y);
  const float t_side = back.at(side.x, side.y) - front.at(side.x, side.y);
  const double expected_centre_m = 2.0 * (ball_radius_m + renderer.splat_radius_m());
  EXPECT_NEAR(t_centre, expected_centre_m, 0.15 * expected_centre_m);
  EXPECT_GT(t_side, 0.0f);
  EXPECT_GT(t_centre, 1.3f * t_side) << "centre " << t_centre << " m, side " << t_side << " m";

  // The composite's own T(p) (thickness view) agrees: brighter through the centre.
  const Rgba8Image grey = renderer.render_to_image(CompositeMode::thickness);
  const glm::ivec2 c_full = project(camera, ball_centre_m, grey.width, grey.height);
  const glm::ivec2 s_full = project(camera, ball_centre_m + right * float(0.75 * ball_radius_m), grey.width, grey.height);
  EXPECT_GT(int(grey.pixel(c_full.x, c_full.y)[0]), int(grey.pixel(s_full.x, s_full.y)[0]) + 20);
}

TEST_F(ValidatedRenderTest, PixelsWithoutFluidEqualTheScene) {
  // §5.2: "In the case T(p) = 0, we simply copy the scene color."
  FluidRenderer renderer(*ctx, ball_scene(), small_settings());
  const OrbitCamera camera = close_camera(renderer);
  renderer.set_camera(camera);
  renderer.set_frame(Frame{});
  const Rgba8Image scene = renderer.render_to_image();
  renderer.set_frame(ball_frame());
  const Rgba8Image with_fluid = renderer.render_to_image();
  const FloatImage coverage = renderer.read_buffer(FluidBuffer::raw_front_depth);
  const float t = renderer.no_fluid_threshold_m();
  size_t empty = 0, changed_inside = 0, inside = 0;
  for (uint32_t y = 0; y < scene.height; ++y)
    for (uint32_t x = 0; x < scene.width; ++x) {
      const bool fluid = coverage.at(std::min(x / 2, coverage.width - 1), std::min(y / 2, coverage.height - 1)) <= t;
      const bool same = std::equal(scene.pixel(x, y), scene.pixel(x, y) + 4, with_fluid.pixel(x, y));
      if (!fluid) {
        ++empty;
        ASSERT_TRUE(same) << "pixel (" << x << ", " << y << ") has no fluid but differs from the scene";
      } else {
        ++inside;
        changed_inside += same ? 0 : 1;
      }
    }
  EXPECT_GT(empty, scene.width * scene.height / 2);
  EXPECT_GT(changed_inside, inside * 9 / 10) << "the fluid must change the picture where it is";
}

TEST_F(ValidatedRenderTest, DebugSpheresDrawParticlesInsteadOfTheFluidSurface) {
  RenderSettings s = small_settings();
  s.debug_spheres = true;
  FluidRenderer renderer(*ctx, ball_scene(), s);
  const OrbitCamera camera = close_camera(renderer);
  renderer.set_camera(camera);
  renderer.set_frame(Frame{});
  const Rgba8Image empty = renderer.render_to_image();
  renderer.set_frame(ball_frame());
  const Rgba8Image spheres = renderer.render_to_image();
  const FloatImage splat = renderer.read_buffer(FluidBuffer::raw_front_depth);
  for (float v : splat.values) ASSERT_GT(v, renderer.no_fluid_threshold_m()) << "no fluid surface in sphere mode";
  const glm::ivec2 c = project(camera, ball_centre_m, spheres.width, spheres.height);
  const uint8_t* p = spheres.pixel(c.x, c.y);
  EXPECT_FALSE(std::equal(p, p + 4, empty.pixel(c.x, c.y)));
  EXPECT_GT(int(p[2]), int(p[0]) + 30) << "fluid particles are drawn blue";
}

TEST_F(ValidatedRenderTest, RefusesImpossibleSettingsWithAClearMessage) {
  RenderSettings s = small_settings();
  s.filter_iterations = -1;
  try {
    FluidRenderer renderer(*ctx, ball_scene(), s);
    FAIL() << "negative filter iterations must be refused";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("filter iterations must be 0..64"), std::string::npos) << e.what();
  }
}

TEST_F(ValidatedRenderTest, ExtinctionGivesEachFluidItsColour) {
  // Eq. 15: through thick fluid the colour tends to F_c with wavelength-dependent extinction F_e.
  // Water absorbs red most (blue-green), honey absorbs blue most (amber).
  auto mean_colour_at_centre = [&](hapfluid::config::FluidLook look) {
    SceneDescription scene = ball_scene();
    scene.look = fluid_look(look);
    FluidRenderer renderer(*ctx, scene, small_settings());
    const OrbitCamera camera = close_camera(renderer);
    renderer.set_camera(camera);
    renderer.set_frame(ball_frame());
    const Rgba8Image image = renderer.render_to_image();
    const glm::ivec2 c = project(camera, ball_centre_m, image.width, image.height);
    glm::vec3 sum(0.0f);
    for (int dy = -10; dy <= 10; ++dy)
      for (int dx = -10; dx <= 10; ++dx) {
        const uint8_t* p = image.pixel(uint32_t(c.x + dx), uint32_t(c.y + dy));
        sum += glm::vec3(p[0], p[1], p[2]);
      }
    return sum / 441.0f;
  };
  const glm::vec3 water = mean_colour_at_centre(hapfluid::config::FluidLook::water);
  const glm::vec3 honey = mean_colour_at_centre(hapfluid::config::FluidLook::honey);
  EXPECT_GT(water.b, water.r + 20.0f) << "water " << water.r << " " << water.g << " " << water.b;
  EXPECT_GT(honey.r, honey.b + 40.0f) << "honey " << honey.r << " " << honey.g << " " << honey.b;
}

TEST_F(ValidatedRenderTest, ContainerWallsShowBehindTheFluidAndNeverInFrontOfIt) {
  // The domain's side walls frame the fluid; the ones between the camera and the fluid are left
  // out, so a user always sees the fluid the haptic device is pushing.
  SceneDescription scene = ball_scene();
  scene.walls = {true, {-0.3f, -0.3f, 0.0f}, {0.3f, 0.3f, 0.4f}, true, true, true, true};
  RenderSettings s = small_settings();
  FluidRenderer renderer(*ctx, scene, s);
  OrbitCamera camera = close_camera(renderer);
  camera.distance_m = 1.2f;  // outside the box, on its -y side
  renderer.set_camera(camera);
  renderer.set_frame(ball_frame());
  const Rgba8Image image = renderer.render_to_image();
  const glm::ivec2 centre = project(camera, ball_centre_m, image.width, image.height);
  const uint8_t* fluid = image.pixel(centre.x, centre.y);
  EXPECT_GT(int(fluid[2]), int(fluid[0]) + 20) << "the ball of water is visible through the near wall's gap";
  // Above the ball: the far (y_max) wall, grey, instead of the blue-grey sky.
  const glm::ivec2 above = project(camera, glm::vec3(0.0f, 0.3f, 0.35f), image.width, image.height);
  const uint8_t* wall = image.pixel(above.x, above.y);
  EXPECT_LT(std::abs(int(wall[0]) - int(wall[2])), 12) << "far wall expected, got " << int(wall[0]) << " "
                                                       << int(wall[1]) << " " << int(wall[2]);
}
