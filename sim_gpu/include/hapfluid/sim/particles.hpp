// Particle storage, structure of arrays (one array per quantity) so that the CPU loops stream
// contiguous floats and the Vulkan backend can mirror each array as one buffer.
//
// Three sets of particles take part in a step:
//  - fluid particles, re-sorted by grid cell every step (their arrays are physically permuted);
//  - static solid particles: the domain walls and static bodies, sorted by cell once at start;
//  - dynamic body particles, grouped per body (body 0's particles first, then body 1's, ...) so
//    per-body force sums read contiguous ranges (§4.3); a cell-sorted copy of them is rebuilt
//    every step for neighbour queries (SortedSolids).
// Solid particles are boundary particles in the sense of Akinci et al. 2012: each carries the
// volume V_b = 1 / sum_k W(x_b - x_k) over the particles of its own solid, so that a fluid
// particle next to a wall or a body sees a full neighbourhood (no particle deficiency).
#pragma once

#include <cstdint>
#include <vector>

namespace hapfluid::sim {

// Kind written to outputs (VTK "kind" field): fluid, wall, body (the body index is separate).
enum class ParticleKind : std::int32_t { fluid = 0, wall = 1, body = 2 };

inline constexpr std::int32_t kWall = -1;  // body index of a domain wall particle

struct FluidParticles {
  std::vector<float> x, y, z;     // position at t, m
  std::vector<float> vx, vy, vz;  // leap-frog velocity at t - dt/2 (after a step: t + dt/2), m/s
  std::vector<float> ax, ay, az;  // acceleration of the last step, m/s^2
  std::vector<float> density;     // eq. 2, kg/m^3
  std::vector<float> pressure;    // eq. 7, Pa
  std::vector<float> volume;      // m / density, m^3
  // 1 / c of gradient_correction.hpp: the pressure force (eq. 5) takes the particle's volume as
  // volume * volume_correction (1 on the rest lattice).
  std::vector<float> volume_correction;
  std::vector<float> viscosity;   // per-particle mu, Pa s (eq. 9)
  // dfsph warm start: the last step's pressure stiffness of the constant-density solve times dt^2
  // and of the divergence-free solve times dt (both then independent of the step size).
  std::vector<float> density_stiffness_dt2, divergence_stiffness_dt;
  // dfsph warm start of the implicit viscosity: the velocity change its last solve made, m/s
  // (zero after a step that took the explicit viscous step).
  std::vector<float> viscous_dvx, viscous_dvy, viscous_dvz;
  std::vector<std::uint32_t> id;  // creation index, unchanged by sorting

  std::size_t size() const { return x.size(); }
  void resize(std::size_t n);
  // Reorders every array so that new[k] = old[order[k]].
  void permute(const std::vector<std::uint32_t>& order);

 private:
  std::vector<float> scratch_f_;
  std::vector<std::uint32_t> scratch_u_;
};

// Solid particles sorted by cell, as neighbour queries read them.
struct SortedSolids {
  std::vector<float> x, y, z, vx, vy, vz;
  std::vector<float> volume;     // Akinci boundary volume, m^3
  std::vector<float> viscosity;  // the solid's mu (eq. 9), Pa s
  std::vector<float> no_slip;    // 1: full eq. 9 friction (bodies); 0: normal damping only (domain walls)
  std::vector<float> pressure;   // contact pressure (dynamic bodies); unused for static solids
  std::vector<std::int32_t> body;  // body index, kWall for walls
  std::vector<std::uint32_t> source;  // index in the unsorted set it was copied from
  std::vector<std::uint32_t> cell_start;

  std::size_t size() const { return x.size(); }
  void resize(std::size_t n);
};

// Dynamic body particles, grouped per body.
struct BodyParticles {
  std::vector<float> x, y, z, vx, vy, vz;      // world position and velocity (eq. 14)
  std::vector<float> rx, ry, rz;               // rest offset from the centre of mass, body axes, m
  std::vector<float> volume, viscosity;
  std::vector<float> pressure;                 // contact pressure from other solids, Pa
  std::vector<float> fx, fy, fz;               // force from the fluid (f^haptic), N
  std::vector<float> cx, cy, cz;               // contact force from other solids, N
  std::vector<std::int32_t> body;

  std::size_t size() const { return x.size(); }
  void resize(std::size_t n);
};

}  // namespace hapfluid::sim
