// The particle passes of the incompressible solver (dfsph_solver.hpp), as free functions over
// [begin, end) of the sorted fluid, compiled twice (AVX2 and baseline x86-64, picked at load
// time). Each writes only the entries of its own range. Internal to sim_gpu.
#pragma once

#include <cstddef>
#include <cstdint>

#include "hapfluid/sim/dfsph_solver.hpp"
#include "hapfluid/sim/model.hpp"
#include "hapfluid/sim/wall_map.hpp"

namespace hapfluid::sim::detail {

// Neighbour pairs (candidates of the 27 cells filtered branch-free into the list), normalised
// density, DFSPH factor, the solids' gradient sum and flux, and neighbour counts.
// The domain walls enter through their volume map, the static and dynamic bodies as particles.
void build_pairs(const SimulationParams& p, const FluidParticles& f, const std::uint32_t* fluid_cell_start,
                 const SortedSolids& statics, const SortedSolids& bodies, const WallMap& walls, std::size_t begin,
                 std::size_t end, PairLists& lists, PairRange* ranges, DfsphFields& out);

// rate[i] = D(rho/rho0)/Dt = sum_j V_j grad W_ij . (v_i - v_j) over fluid and solid neighbours,
// 1/s; the dynamic bodies' particles with their velocities in `bodies` (static solids are at rest).
// The fluid's velocities are d.velocity (packed for the solve). With body_pairs false the
// dynamic bodies' share is left out, for the caller to subtract per body from their rigid
// velocities (BodySolveCoupling::subtract_flux, inside the coupled solves).
void density_rate(const SortedSolids& bodies, const DfsphFields& d, const PairLists& lists, const PairRange* ranges,
                  std::size_t begin, std::size_t end, float* rate, bool body_pairs = true);

// v_i -= dt (sum_fluid (k_i + k_j) V_j grad W_ij + k_i sum_solids Psi_b grad W_ib), k = the
// stiffness increments of this iteration.
// On d.velocity.
void apply_stiffness(DfsphFields& d, const PairLists& lists, const PairRange* ranges, std::size_t begin,
                     std::size_t end, float dt);

// Gravity and XSPH (as an acceleration over dt) into ax, ay, az; viscosity is implicit
// (implicit_viscosity.hpp).
void non_pressure_accelerations(const SimulationParams& p, FluidParticles& f, const DfsphFields& d,
                                const PairLists& lists, const PairRange* ranges, std::size_t begin, std::size_t end,
                                float dt);

// Force of the fluid on the dynamic body particles: the opposite of the terms the fluid
// particles [begin, end) received from them, read from their pair lists into `sums` (3 per
// particle of the cell-sorted body view, this slot's own, zeroed first; the caller adds the
// slots). The viscous part is taken with the velocities the viscosity solve ended on (right
// after it); the pressure part, this step's total stiffness of both solves, after the solves.
enum class BodyForcePart { viscous, pressure };
void body_pair_forces(const SimulationParams& p, const FluidParticles& f, const DfsphFields& d, const SortedSolids& bodies,
                      BodyForcePart part, const PairLists& lists, const PairRange* ranges, std::size_t begin,
                      std::size_t end, float* sums);

}  // namespace hapfluid::sim::detail
