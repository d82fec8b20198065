// The optical parameters of equation 15 for one fluid: colour F_c, wavelength-dependent
// extinction F_e, refraction strength beta, specular colour k_s and exponent alpha.
#pragma once

#include <glm/glm.hpp>

#include "hapfluid/config/scene.hpp"

namespace hapfluid::render {

struct FluidLook {
  glm::vec3 colour{0.1f, 0.3f, 0.5f};            // F_c
  glm::vec3 extinction_per_m{6.0f, 2.5f, 1.5f};  // F_e, per metre of thickness (r, g, b)
  float refraction_uv_per_m = 0.08f;             // beta: scene lookup offset, in uv per metre
  glm::vec3 specular{0.6f};                      // k_s
  float specular_exponent = 60.0f;               // alpha
};

// The presets a scene names with fluid.look (water, batter, honey, syrup).
FluidLook fluid_look(config::FluidLook preset);

}  // namespace hapfluid::render
