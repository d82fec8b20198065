// The implicit viscosity of the incompressible solver (Weiler, Koschier, Brand & Bender 2018, "A
// physically consistent implicit viscosity solver for SPH fluids"): the SPH Laplacian of
// Monaghan 2005 (the explicit solver's operator) applied to the velocities at the end of the
// step, so that no viscosity, however high, limits the step. Per fluid particle i:
//   v_i - dt sum_j c_ij ((v_i - v_j) . x_ij) / (|x_ij|^2 + 0.01 h^2) V_j grad W_ij = v*_i,
// c_ij = 2 (d + 2) mu_ij / rho0 times 2 / (rho_i + rho_j) / rho0 for fluid pairs (symmetric, so
// the system is symmetric positive definite and conjugate gradients apply), mu_ij the mean of
// both viscosities; solids (static and dynamic body particles) with their own viscosity and
// known velocity move to the right-hand side; the domain walls, at rest and at the fluid's
// viscosity, add to the diagonal alone (their friction integrals, wall_map.hpp). Passes over
// [begin, end) of the sorted fluid, reading the step's pair lists; internal to sim_gpu.
#pragma once

#include <cstddef>

#include "hapfluid/sim/dfsph_solver.hpp"
#include "hapfluid/sim/model.hpp"
#include "hapfluid/sim/wall_map.hpp"

namespace hapfluid::sim::detail {

// 2 (d + 2) of the SPH Laplacian of a velocity field in d = 3 dimensions (Monaghan 2005); the
// bodies' share of the viscous terms (dfsph_passes.hpp) must use the same.
inline constexpr float kLaplacianFactor = 10.0f;

// The first pass of a solve, on the velocities v* in d.visc_b, the solve's start v0 in d.velocity
// (w: rho / rho0) and the positions in d.position (w: the particle's viscosity):
// b = v* - dt sum_solids c (v_b . x) / d grad into d.visc_b, the walls' share of the diagonal,
// the Jacobi preconditioner (the inverse of the system's diagonal, per component) into the
// viscosity fields, and K v0 into cg_ax, cg_ay, cg_az.
void viscosity_rhs(const SimulationParams& p, const SortedSolids& statics, const SortedSolids& bodies,
                   const WallMap& walls, const PairLists& lists, const PairRange* ranges, std::size_t begin,
                   std::size_t end, float dt, DfsphFields& d);

// out = K v for the velocity field (vx, vy, vz) (3 arrays over the fluid).
void viscosity_apply(const SimulationParams& p, const SortedSolids& statics, const SortedSolids& bodies,
                     const DfsphFields& d, const PairLists& lists, const PairRange* ranges, std::size_t begin,
                     std::size_t end, float dt, const float* vx, const float* vy, const float* vz, float* ox, float* oy,
                     float* oz);

}  // namespace hapfluid::sim::detail
