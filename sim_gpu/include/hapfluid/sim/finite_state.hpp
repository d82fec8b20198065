// The divergence check every backend runs on its state (the CPU solver after each frame, the
// Vulkan solver once its particles are read back): a non-finite fluid particle, body or body
// particle stops the run with a message naming it, the quantity, its value and the scene keys
// that would fix it.
#pragma once

#include "hapfluid/sim/model.hpp"

namespace hapfluid::sim {

// Throws std::runtime_error for the first non-finite fluid particle (position, velocity), body
// (position, orientation, velocities) or dynamic body particle, in that order.
void check_finite_state(const SimulationModel& model, double time_s);

}  // namespace hapfluid::sim
