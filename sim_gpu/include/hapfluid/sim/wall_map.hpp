// The domain box's walls as continuous solids for the incompressible solver: a volume map in the
// sense of Bender et al. 2019 ("Volume maps: an implicit boundary representation for SPH"),
// which for a plane is a function of the distance alone. A fluid particle at distance d from a
// wall gets the wall's share of its density, the kernel integrated over the half-space behind
// the wall, and the gradient of that share; no wall particles take part in the fluid's step.
// A continuous wall has no gaps between boundary particles for the fluid to be pressed into,
// and no lattice for the fluid's first layer to slide over.
//
// Two calibrations make a fluid lattice start exactly at rest: the wall surface sits `offset_m`
// behind the box face so that a particle of the first layer (half a spacing from the face) has
// exactly the rest density, and the gradient is scaled so that its pair gradients and the wall's
// cancel there, as they do in the bulk. Where walls meet, the share of the union of their
// half-spaces is 1 - prod (1 - V_w) (WallMap::sample).
//
// The walls also take part in the implicit viscosity, as the wall particles of the weakly
// compressible solver do (no-slip, at the fluid's viscosity): the SPH Laplacian's solid term
// sum_b V_b ((v_i - v_b) . x_ib) / (|x_ib|^2 + 0.01 h^2) grad W_ib, with the wall a continuum
// at rest, is the integral over the half-space of (-W'(r) / r) / (r^2 + 0.01 h^2) x x^T, times
// -v_i: diagonal in the wall's frame, one value for the normal and one for the tangents
// (WallMap::friction). The wall's points carry the fluid's velocity extrapolated through zero at
// the surface (Morris et al. 1997), so the fluid sticks at the surface rather than somewhere
// inside the wall. Without it a volume-mapped wall is free-slip: a viscous fluid slides along
// the floor as on ice.
#pragma once

#include <vector>

#include "hapfluid/sim/cubic_kernel.hpp"
#include "hapfluid/sim/model.hpp"

namespace hapfluid::sim {

struct WallMap {
  bool enabled[6] = {false, false, false, false, false, false};  // x_min, x_max, y_min, y_max, floor, ceiling
  float face[6] = {0, 0, 0, 0, 0, 0};                              // the box face, m
  float offset_m = 0;
  float gradient_scale = 1;
  float h = 0;
  // Tables over u = d + offset in [-h, h] (d the distance from the face into the fluid):
  // share of density (rho / rho0) and the magnitude of its gradient, 1/m.
  std::vector<float> share, slope;
  // The friction integrals over the same u, 1/m^2: x_n^2 (normal) and x_t^2 (one tangent).
  std::vector<float> friction_normal, friction_tangent;
  float du = 0;

  bool any() const {
    for (bool e : enabled)
      if (e) return true;
    return false;
  }
  // Adds the walls' density share and its gradient (pointing into the walls) at a position.
  void sample(float x, float y, float z, float& density_hat, float& gx, float& gy, float& gz) const;
  // Adds the walls' friction integrals per axis at a position (each wall within reach: its
  // normal integral on its own axis, the tangential one on the other two), 1/m^2.
  void friction(float x, float y, float z, float& fx, float& fy, float& fz) const;
};

// The map of the enabled walls of a box, for the cubic kernel and fluid lattice spacing given.
WallMap make_wall_map(const float box_lo[3], const float box_hi[3], const bool low_wall[3], const bool high_wall[3],
                      const CubicKernel& kernel, double spacing_m);

// The walls of the scene's domain box (those its clamp encloses), for the incompressible kernel.
WallMap domain_wall_map(const SimulationParams& p);

// The static solids the incompressible solver's fluid meets as particles: the static bodies'
// particles, sorted by cell on the model's grid. The domain walls are left out: the fluid sees
// them through their volume map (their particles stay in the model for body contacts and
// outputs).
SortedSolids static_solids_beside_walls(const SimulationModel& model);

}  // namespace hapfluid::sim
