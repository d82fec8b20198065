// Everything a scene defines, turned into particles and bodies ready to step: built once by
// build_model (scene_setup.cpp) and then owned by a solver backend.
#pragma once

#include <string>
#include <vector>

#include "hapfluid/config/motion.hpp"
#include "hapfluid/config/scene.hpp"
#include "hapfluid/sim/coupling.hpp"
#include "hapfluid/sim/cubic_kernel.hpp"
#include "hapfluid/sim/kernels.hpp"
#include "hapfluid/sim/math.hpp"
#include "hapfluid/sim/neighbour_grid.hpp"
#include "hapfluid/sim/particles.hpp"
#include "hapfluid/sim/rigid_body.hpp"

namespace hapfluid::sim {

// What the incompressible solver (dfsph) needs beyond the common parameters.
struct IncompressibleParams {
  CubicKernel kernel;
  float max_density_error = 0.001f;     // mean (rho* - rho0) / rho0 at which the density solve stops
  float max_divergence_error = 0.001f;  // mean |D rho / Dt| dt / rho0 at which the divergence solve stops
  // Error passes each solve takes at least: the density solve 2 (its first pass sees only the warm
  // start), the divergence solve 1, as in Bender & Koschier's own implementation: the divergence
  // left after the last step's density solve is mostly what its warm start removes.
  int min_density_iterations = 2;
  int min_divergence_iterations = 1;
  int max_iterations = 100;
  float xsph_fraction = 0;              // fluid.xsph_fraction
  double settle_s = 0;                  // fluid.settle_s
  // Fewer neighbours than this: a particle at the free surface, left out of the divergence solve
  // (its neighbourhood is too thin for a divergence estimate; it would pull the surface apart).
  int min_divergence_neighbours = 20;
};

struct SimulationParams {
  config::PressureSolver solver = config::PressureSolver::wcsph;
  IncompressibleParams incompressible;  // solver = dfsph
  KernelConstants kernel;
  float rest_density_kg_m3 = 1000;
  float stiffness = 0;            // k of eq. 7 (= c^2), m^2/s^2
  float speed_of_sound_m_s = 0;   // sqrt(k), for the CFL bound
  float contact_damping_pa_s = 0; // alpha rho0 c h of the contact artificial viscosity (contact_damping.hpp)
  float fluid_particle_mass_kg = 0;
  float particle_spacing_m = 0;
  float fluid_viscosity_pa_s = 0;
  Vec3 gravity_m_s2;
  float box_lo[3] = {0, 0, 0}, box_hi[3] = {0, 0, 0};  // the domain box
  // Last-resort clamp for fluid positions: the first wall layer (half a spacing behind the face)
  // on walled sides (reaching it is a leak), the box face on open sides.
  float clamp_lo[3] = {0, 0, 0}, clamp_hi[3] = {0, 0, 0};
  GridGeometry grid;
  double fixed_dt_s = 0;          // 0: CFL
  double cfl = 0.4;
  double max_dt_s = 0.002;
  double frame_rate_hz = 60;
};

// The last-resort clamp of one coordinate of a fluid particle moving to x with velocity v: put
// back at clamp_lo/clamp_hi with its outward velocity removed. Returns whether it acted (a
// fault: the walls alone must hold the fluid).
inline bool clamp_to_domain(const SimulationParams& p, int axis, float& x, float& v) {
  if (x < p.clamp_lo[axis]) {
    x = p.clamp_lo[axis], v = v < 0 ? 0 : v;
    return true;
  }
  if (x > p.clamp_hi[axis]) {
    x = p.clamp_hi[axis], v = v > 0 ? 0 : v;
    return true;
  }
  return false;
}

struct DeviceInfo {
  std::string name;
  config::ScriptedMotion motion;  // scripted hand (batch runs), or the start pose of a rig device
};

struct SimulationModel {
  std::string scene_name;
  SimulationParams params;
  FluidParticles fluid;
  SortedSolids static_solids;           // walls and static bodies, sorted by cell
  BodyParticles body_particles;         // dynamic bodies, grouped per body
  std::vector<RigidBody> bodies;        // scene order
  std::vector<DeviceInfo> devices;
  std::vector<VirtualCoupling> couplings;
  std::size_t wall_particle_count = 0;
  std::size_t static_body_particle_count = 0;
};

// Builds the particles and bodies of a loaded scene. Throws std::runtime_error naming the scene
// file, the body and the fix when the scene cannot be simulated (a body overlapping a wall, a
// sampling spacing too coarse to hold fluid, an open mesh, ...).
SimulationModel build_model(const config::Scene& scene);

// Mass of one fluid particle such that a cubic lattice of the given spacing has exactly the rest
// density under the poly6 sum of eq. 2.
double lattice_particle_mass(double rest_density, double spacing, double support_radius);

// The same two for the cubic spline of the incompressible solver (cubic_kernel.hpp).
double cubic_lattice_particle_mass(double rest_density, double spacing, double support_radius);
double cubic_lattice_gradient_moment(double spacing, double support_radius);

// First moment sum_j V_j (z_j - z_i) dW/dz of the spiky gradient over a cubic lattice (1 for an
// exact gradient estimate).
double lattice_gradient_moment(double spacing, double support_radius);

}  // namespace hapfluid::sim
