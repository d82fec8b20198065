// Shared set-up of the Vulkan render tests: a context with VK_LAYER_KHRONOS_validation on (any
// warning or error fails the test), and a small fixed scene: a ball of water in front of the
// checkered floor.
#pragma once

#include <gtest/gtest.h>

#include <memory>

#include "hapfluid/render/fluid_renderer.hpp"
#include "hapfluid/render/synthetic_source.hpp"

namespace hapfluid::render::test {

constexpr double particle_radius_m = 0.01;
constexpr double ball_radius_m = 0.08;
const glm::vec3 ball_centre_m{0.0f, 0.0f, 0.12f};

class ValidatedRenderTest : public ::testing::Test {
 protected:
  void SetUp() override { ctx = std::make_unique<vk::Context>(context_options(true, false)); }
  void TearDown() override {
    ctx->destroy_device();  // leaks are reported here, while the counters are still readable
    std::string all;
    for (const auto& m : ctx->validation_messages()) all += m + "\n";
    EXPECT_EQ(ctx->validation_counts().errors, 0u) << all;
    EXPECT_EQ(ctx->validation_counts().warnings, 0u) << all;
  }

  static SceneDescription ball_scene() { return synthetic_scene(particle_radius_m); }
  static Frame ball_frame() {
    Frame f;
    f.fluid_m = fluid_ball(ball_centre_m, ball_radius_m, particle_radius_m);
    return f;
  }
  static OrbitCamera close_camera(const FluidRenderer& r) {
    OrbitCamera c = r.camera();
    c.target_m = ball_centre_m;
    c.distance_m = 0.7f;
    return c;
  }
  // Pixel of a world point in an image of width x height seen by `camera`.
  static glm::ivec2 project(const OrbitCamera& camera, glm::vec3 point, uint32_t width, uint32_t height) {
    glm::vec4 clip = camera.projection(float(width) / float(height)) * camera.view() * glm::vec4(point, 1.0f);
    glm::vec2 ndc = glm::vec2(clip) / clip.w;
    return glm::ivec2((ndc * 0.5f + 0.5f) * glm::vec2(width, height));
  }

  std::unique_ptr<vk::Context> ctx;
};

}  // namespace hapfluid::render::test
