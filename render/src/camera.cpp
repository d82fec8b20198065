#include "hapfluid/render/camera.hpp"

#include <algorithm>
#include <cmath>

#include <glm/gtc/matrix_transform.hpp>

namespace hapfluid::render {

glm::vec3 OrbitCamera::eye_m() const {
  const float c = std::cos(pitch_rad);
  return target_m + distance_m * glm::vec3(c * std::cos(yaw_rad), c * std::sin(yaw_rad), std::sin(pitch_rad));
}

glm::mat4 OrbitCamera::view() const { return glm::lookAtRH(eye_m(), target_m, glm::vec3(0, 0, 1)); }

glm::mat4 OrbitCamera::projection(float aspect) const {
  glm::mat4 p = glm::perspectiveRH_ZO(fov_y_rad, aspect, near_m, far_m);
  p[1][1] *= -1.0f;
  return p;
}

void OrbitCamera::orbit(float delta_yaw_rad, float delta_pitch_rad) {
  yaw_rad += delta_yaw_rad;
  pitch_rad = std::clamp(pitch_rad + delta_pitch_rad, -1.55f, 1.55f);
}

void OrbitCamera::zoom(float factor) { distance_m = std::max(distance_m * factor, 2.0f * near_m); }

}  // namespace hapfluid::render
