#include "hapfluid/render/fluid_look.hpp"

namespace hapfluid::render {

// Extinction is per metre of fluid along the view ray: larger for red than for blue makes water
// blue-green; batter is nearly opaque within a centimetre; honey and syrup absorb blue most.
FluidLook fluid_look(config::FluidLook preset) {
  switch (preset) {
    case config::FluidLook::water:
      return {{0.10f, 0.30f, 0.50f}, {6.0f, 2.5f, 1.5f}, 0.08f, glm::vec3(0.6f), 60.0f};
    case config::FluidLook::batter:
      return {{0.92f, 0.80f, 0.55f}, {150.0f, 160.0f, 190.0f}, 0.01f, glm::vec3(0.25f), 20.0f};
    case config::FluidLook::honey:
      return {{0.80f, 0.45f, 0.05f}, {6.0f, 20.0f, 60.0f}, 0.06f, glm::vec3(0.7f), 80.0f};
    case config::FluidLook::syrup:
      return {{0.40f, 0.15f, 0.03f}, {25.0f, 50.0f, 90.0f}, 0.05f, glm::vec3(0.6f), 70.0f};
  }
  return {};
}

}  // namespace hapfluid::render
