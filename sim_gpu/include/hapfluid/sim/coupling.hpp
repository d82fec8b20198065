// Virtual coupling (§4.4, Colgate et al. 1995): a spring-damper, linear and angular, between a
// device handle and the grasp frame on a rigid body. The coupling wrench acts on the body; its
// opposite is the wrench rendered on the device (Algorithm 2, lines 7 and 9). Any number of
// devices may hold one body (bimanual, §6.4.4).
//
// The body step treats the coupling springs and dampers implicitly (one 6x6 solve per body), so
// a stiff coupling on a light tool stays stable at the SPH time step.
#pragma once

#include <cstddef>
#include <vector>

#include "hapfluid/config/types.hpp"
#include "hapfluid/sim/math.hpp"
#include "hapfluid/sim/rigid_body.hpp"

namespace hapfluid::sim {

struct DeviceState {
  Vec3 position;
  Quat orientation;
  Vec3 linear_velocity;
  Vec3 angular_velocity;  // world frame
};
DeviceState device_state_from(const config::PoseTwist& twist);

// The hand's pose dt later, moving on with its twist now. The coupling is implicit (below): it
// pulls the body toward where it holds the hand at the step's end, so a live sim given a moving
// hand's pose now lags it by a step, and the 1 kHz loop, which renders each sample against the
// hand's pose until the next one, adds a spring force K v dt against the stroke (haptic-sim
// --live couples the hand at its pose at the end of each step).
DeviceState device_state_after(DeviceState state, double dt);

struct VirtualCoupling {
  std::size_t device = 0;
  std::size_t body = 0;
  Vec3 grasp_position;     // handle position in the mesh frame, m
  Quat grasp_orientation;  // handle orientation relative to the mesh frame
  double linear_stiffness_n_per_m = 0, linear_damping_n_s_per_m = 0;
  double angular_stiffness_nm_per_rad = 0, angular_damping_nm_s_per_rad = 0;

  // Result of the last step: the wrench to render on the device (force at the handle, torque).
  Vec3 device_force, device_torque;
};

// Where the coupling holds its body, in the world, at the body's current pose.
Vec3 grasp_in_world(const RigidBody& body, const VirtualCoupling& c);

// The body's implicit step as a 6x6 system A u = rhs for u = (v, w) at t + dt/2 (Algorithm 2,
// lines 6-7): A is the mass matrix plus each coupling's dt (b + dt k) J^T J; rhs is the
// momentum plus dt times the external force and torque summed into the body, gravity and the
// couplings' spring and damper terms at the current pose. Linear in the external force: a change
// dF of it changes u by dt A^-1 dF, which is what a pressure solve coupled to the body needs.
struct BodySystem {
  double a[6][6] = {};
  double rhs[6] = {};
};
BodySystem body_system(const RigidBody& body, const std::vector<VirtualCoupling*>& couplings,
                       const std::vector<DeviceState>& devices, const Vec3& gravity, double dt);

// x = A^-1 b for the 6x6 systems here (SPD; Gaussian elimination with partial pivoting).
void solve6(const double a[6][6], const double b[6], double x[6]);

// One leap-frog step of a dynamic body (Algorithm 2, lines 6-8): external force and torque
// (fluid + contact, already summed into the body), gravity and the couplings holding it.
// Updates the state and the couplings' device wrenches.
void integrate_body(RigidBody& body, std::vector<VirtualCoupling*>& couplings, const std::vector<DeviceState>& devices,
                    const Vec3& gravity, double dt);

}  // namespace hapfluid::sim
