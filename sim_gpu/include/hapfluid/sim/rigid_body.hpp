// Rigid bodies of the unified particle model (§4.2, Algorithm 2): state, per-step force and
// torque sums, and the leap-frog integration of position and orientation.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "hapfluid/config/types.hpp"
#include "hapfluid/sim/math.hpp"

namespace hapfluid::sim {

struct RigidBody {
  std::string name;
  bool dynamic = true;
  double mass_kg = 0;
  double volume_m3 = 0;                 // of the closed mesh
  Mat3 inertia_body;                    // about the centre of mass, body (mesh) axes, kg m^2
  Mat3 inertia_body_inverse;
  Vec3 com_in_mesh_frame;               // centre of mass in the scaled mesh frame, m
  double viscosity_pa_s = 0;            // eq. 9

  // State: centre of mass position, orientation of the mesh frame, leap-frog velocities
  // (at t - dt/2 before a step, t + dt/2 after it), angular momentum (world).
  Vec3 position;
  Quat orientation;
  Vec3 linear_velocity;
  Vec3 angular_velocity;
  Vec3 angular_momentum;

  // Dynamic bodies: their particles are [first_particle, first_particle + particle_count) of
  // BodyParticles. Static bodies live among the static solids.
  std::uint32_t first_particle = 0, particle_count = 0;

  // Results of the last step (world frame, torques about the centre of mass).
  Vec3 fluid_force, fluid_torque;       // eqs. 10-12: sums of f^haptic over the body's particles
  Vec3 contact_force, contact_torque;   // from other bodies and walls
  Vec3 coupling_force, coupling_torque; // from the virtual couplings (sum over devices)

  Mat3 rotation() const { return rotation_matrix(orientation); }
  Mat3 world_inertia() const;
  Mat3 world_inverse_inertia() const;
  // The pose of the mesh frame (what the scene gives and the renderer draws).
  config::Pose mesh_pose() const;
  Vec3 velocity_at(const Vec3& world_point) const {  // eq. 14
    return linear_velocity + cross(angular_velocity, world_point - position);
  }
};

}  // namespace hapfluid::sim
