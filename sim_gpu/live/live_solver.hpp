// What the live loop needs from a simulation backend (CpuSolver or vulkan::VulkanSolver), so
// that one loop (live_runner.cpp) does the shm publishing, wall-clock following, device
// matching, CSVs and stats for both.
//
// Per step the loop sets device poses, steps, and reads bodies and couplings from model(): both
// backends keep those on the host (the Vulkan backend integrates the bodies on the host between
// its two submissions, vulkan_solver.hpp). Fluid particles live on the device with Vulkan; they
// come back only at the frame rate, in sync_and_check_finite().
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "hapfluid/sim/solver.hpp"
#include "hapfluid/sim/model.hpp"

namespace hapfluid::sim {

// The live loop drives the one Solver interface (hapfluid/sim/solver.hpp).
using LiveSolver = Solver;

}  // namespace hapfluid::sim
