// Contacts between solids (body-body and body-wall), the same for every CPU method: a contact
// pressure k rho0 sum_c V_c W over the particles of *other* solids (zero when a body touches
// nothing) and the damped pair force of contact_damping.hpp. Internal to sim_gpu.
#pragma once

#include <cstddef>

#include "hapfluid/sim/body_reach.hpp"
#include "hapfluid/sim/model.hpp"

namespace hapfluid::sim::detail {

// Contact pressure of the body particles [begin, end) of the cell-sorted view; written to the
// view and to the grouped body particles (through view.source).
void body_contact_pressure(const SimulationParams& p, const SortedSolids& statics, SortedSolids& view,
                           BodyParticles& bodies, const BodyReach& reach, std::size_t begin, std::size_t end);

// Contact force (cx, cy, cz) on the grouped body particles [begin, end): pressure, eq. 9 with the
// solids' viscosities and the artificial viscosity of approaching pairs. Returns whether any of
// them touches another solid.
bool body_contact_forces(const SimulationParams& p, const SortedSolids& statics, const SortedSolids& view,
                         BodyParticles& bodies, const BodyReach& reach, std::size_t begin, std::size_t end);

}  // namespace hapfluid::sim::detail
