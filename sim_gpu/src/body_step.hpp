// The rigid-body half of a step, the same for every CPU method: the cell-sorted view of the
// dynamic body particles that neighbour queries read, and Algorithm 2 (per-body sums of the
// particle forces, gravity, couplings, integration, eq. 14). Internal to sim_gpu.
#pragma once

#include <vector>

#include "hapfluid/sim/coupling.hpp"
#include "hapfluid/sim/model.hpp"
#include "hapfluid/sim/thread_pool.hpp"

namespace hapfluid::sim::detail {

// Sorts the dynamic body particles by cell into `view` (velocities, volumes, viscosities).
void sort_body_view(const GridGeometry& grid, const BodyParticles& bodies, CellSort& sort, SortedSolids& view);

// Per dynamic body, the sums of its particles' fluid and contact forces and torques about the
// centre of mass (eqs. 10-12, in double, in particle order).
void sum_body_forces(SimulationModel& m);

// Algorithm 2: per body, sums of the particles' fluid and contact forces and torques (eqs. 10-12,
// in double, in particle order), then integrate_body, then the particles placed by eq. 14.
void step_bodies(SimulationModel& m, std::vector<std::vector<VirtualCoupling*>>& couplings_of_body,
                 const std::vector<DeviceState>& devices, double dt, ThreadPool& pool);

// Body particle velocities from their bodies' (eq. 14), for the start state.
void set_body_particle_velocities(SimulationModel& m);

}  // namespace hapfluid::sim::detail
