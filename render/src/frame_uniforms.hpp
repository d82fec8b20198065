// Host mirror of shaders/common.glsl's FrameUniforms (std140: vec4s and mat4s only).
#pragma once

#include <glm/glm.hpp>

namespace hapfluid::render {

// Depth written where no particle covers a pixel; anything above the threshold is "no fluid".
constexpr float no_fluid_depth_m = 1.0e6f;
constexpr float no_fluid_threshold_depth_m = 1.0e5f;

struct FrameUniforms {
  glm::mat4 view;
  glm::mat4 proj;
  glm::vec4 light_dir_view;
  glm::vec4 viewport;
  glm::vec4 half_viewport;
  glm::vec4 splat;
  glm::vec4 fluid_colour;
  glm::vec4 extinction;
  glm::vec4 specular;
  glm::vec4 refraction;
  glm::vec4 floor_params;
};
static_assert(sizeof(FrameUniforms) == 2 * 64 + 9 * 16, "must match common.glsl");

}  // namespace hapfluid::render
