// The two hot particle passes of the CPU backend (density and fluid forces), as free functions
// compiled twice (AVX2 and baseline x86-64, picked at load time). Internal to sim_gpu.
//
// The density pass walks the 27 grid cells around each fluid particle (about 8 times more
// candidates than neighbours at h = 2 spacings), sums eq. 2 over them and keeps the candidates
// within h in a neighbour list; the force pass then visits only true neighbours. Lists live in
// one buffer per slot of the thread pool: a slot covers the same particles in both passes.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "hapfluid/sim/model.hpp"
#include "hapfluid/sim/neighbour_lists.hpp"

namespace hapfluid::sim::detail {

// Eq. 2 with the boundary contribution rho0 V_b W, then eq. 7 (clamped at zero), V = m / rho and
// the volume correction 1 / c (gradient_correction.hpp); fills the neighbour lists of [begin, end).
void density_pass(const SimulationParams& p, FluidParticles& f, const std::uint32_t* fluid_cell_start,
                  const SortedSolids& statics, const SortedSolids& bodies, std::size_t begin, std::size_t end,
                  NeighbourLists& lists, NeighbourRange* ranges);

// Pressure (eq. 5, pair terms scaled by 1 / (c_i c_j)) and viscosity (eqs. 6, 9) accelerations
// plus gravity over the neighbour lists;
// returns the largest squared acceleration of the range.
float fluid_force_pass(const SimulationParams& p, FluidParticles& f, const SortedSolids& statics,
                       const SortedSolids& bodies, std::size_t begin, std::size_t end, const NeighbourLists& lists,
                       const NeighbourRange* ranges);

}  // namespace hapfluid::sim::detail
