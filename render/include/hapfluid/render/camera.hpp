// An orbit camera around a target point, z up (the scene convention). Windowed mode drags it
// with the mouse; headless mode uses the scene's default or the command line's values.
#pragma once

#include <glm/glm.hpp>

namespace hapfluid::render {

struct OrbitCamera {
  glm::vec3 target_m{0.0f};
  float distance_m = 1.5f;
  float yaw_rad = -1.5707963f;  // camera on the -y side, looking along +y
  float pitch_rad = 0.45f;      // above the horizon
  float fov_y_rad = 0.7853982f; // 45 degrees
  float near_m = 0.02f;
  float far_m = 50.0f;

  glm::vec3 eye_m() const;
  glm::mat4 view() const;
  // Right-handed, Vulkan clip space: y down, depth in [0, 1].
  glm::mat4 projection(float aspect) const;

  void orbit(float delta_yaw_rad, float delta_pitch_rad);  // pitch kept inside (-89, 89) degrees
  void zoom(float factor);                                  // distance *= factor, kept > near
};

}  // namespace hapfluid::render
