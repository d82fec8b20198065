#include "hapfluid/sim/rigid_body.hpp"

#include <cmath>
#include <utility>

#include "hapfluid/sim/coupling.hpp"

namespace hapfluid::sim {

Mat3 RigidBody::world_inertia() const {
  const Mat3 r = rotation();
  return r * inertia_body * transpose(r);
}

Mat3 RigidBody::world_inverse_inertia() const {
  const Mat3 r = rotation();
  return r * inertia_body_inverse * transpose(r);
}

config::Pose RigidBody::mesh_pose() const {
  const Vec3 origin = position - rotate(orientation, com_in_mesh_frame);
  return config::Pose{{origin.x, origin.y, origin.z}, {orientation.w, orientation.x, orientation.y, orientation.z}};
}

DeviceState device_state_from(const config::PoseTwist& t) {
  return {from_config(t.pose.position_m), from_config(t.pose.orientation), from_config(t.linear_velocity_m_s),
          from_config(t.angular_velocity_rad_s)};
}

DeviceState device_state_after(DeviceState s, double dt) {
  s.position = s.position + s.linear_velocity * dt;
  s.orientation = normalized(rotation_from_vector(s.angular_velocity * dt) * s.orientation);
  return s;
}

Vec3 grasp_in_world(const RigidBody& body, const VirtualCoupling& c) {
  return body.position + body.rotation() * (c.grasp_position - body.com_in_mesh_frame);
}

namespace {

// Cross-product matrix [r]x, so that [r]x w = r x w.
Mat3 skew(const Vec3& r) {
  Mat3 s;
  s.m[0][1] = -r.z; s.m[0][2] = r.y;
  s.m[1][0] = r.z;  s.m[1][2] = -r.x;
  s.m[2][0] = -r.y; s.m[2][1] = r.x;
  return s;
}

// A linear spring-damper at the grasp point p (Algorithm 2, line 7): its arm from the centre of
// mass, the spring's stretch x_d - p and the angular error, at the body's current pose.
struct CouplingTerms {
  Vec3 r, spring, theta;
};

CouplingTerms coupling_terms(const RigidBody& body, const VirtualCoupling& c, const DeviceState& d) {
  const Vec3 grasp_world = grasp_in_world(body, c);
  const Quat grasp_orientation = normalized(body.orientation * c.grasp_orientation);
  return {grasp_world - body.position, d.position - grasp_world,
          rotation_vector(d.orientation * conjugate(grasp_orientation))};
}

}  // namespace

void solve6(const double a_in[6][6], const double b_in[6], double x[6]) {
  double a[6][6], b[6];
  for (int r = 0; r < 6; ++r) {
    b[r] = b_in[r];
    for (int c = 0; c < 6; ++c) a[r][c] = a_in[r][c];
  }
  for (int col = 0; col < 6; ++col) {
    int pivot = col;
    for (int r = col + 1; r < 6; ++r)
      if (std::abs(a[r][col]) > std::abs(a[pivot][col])) pivot = r;
    if (pivot != col) {
      for (int c = 0; c < 6; ++c) std::swap(a[col][c], a[pivot][c]);
      std::swap(b[col], b[pivot]);
    }
    for (int r = col + 1; r < 6; ++r) {
      const double f = a[r][col] / a[col][col];
      for (int c = col; c < 6; ++c) a[r][c] -= f * a[col][c];
      b[r] -= f * b[col];
    }
  }
  for (int r = 5; r >= 0; --r) {
    double s = b[r];
    for (int c = r + 1; c < 6; ++c) s -= a[r][c] * x[c];
    x[r] = s / a[r][r];
  }
}

BodySystem body_system(const RigidBody& body, const std::vector<VirtualCoupling*>& couplings,
                       const std::vector<DeviceState>& devices, const Vec3& gravity, double dt) {
  // Generalised velocity u = (v, w) at t - dt/2; mass matrix diag(m 1, I_world).
  BodySystem sys;
  const Mat3 inertia = body.world_inertia();
  const Vec3 force = body.fluid_force + body.contact_force + gravity * body.mass_kg;  // Algorithm 2, line 6
  const Vec3 torque = body.fluid_torque + body.contact_torque;
  for (int i = 0; i < 3; ++i) {
    sys.a[i][i] = body.mass_kg;
    for (int j = 0; j < 3; ++j) sys.a[3 + i][3 + j] = inertia.m[i][j];
  }
  const Vec3 momentum = body.linear_velocity * body.mass_kg;
  const Vec3 angular = inertia * body.angular_velocity;
  for (int i = 0; i < 3; ++i) {
    sys.rhs[i] = momentum[i] + dt * force[i];
    sys.rhs[3 + i] = angular[i] + dt * torque[i];
  }
  // Couplings (line 7): velocity of the grasp point J u = v + w x r with J = [1, -[r]x];
  // generalised force J^T F = (F, r x F). Implicit in u(t + dt/2):
  // F = k (x_d - p - dt J u') + b (v_d - J u'), tau = k_a (theta - dt w') + b_a (w_d - w').
  for (const VirtualCoupling* c : couplings) {
    const DeviceState& d = devices[c->device];
    const CouplingTerms t = coupling_terms(body, *c, d);
    const double cl = dt * (c->linear_damping_n_s_per_m + dt * c->linear_stiffness_n_per_m);
    const double ca = dt * (c->angular_damping_nm_s_per_rad + dt * c->angular_stiffness_nm_per_rad);
    // J^T J = [[1, -S], [S^T, S^T S]] with S = [r]x (S^T = -S).
    const Mat3 s = skew(t.r);
    const Mat3 sts = transpose(s) * s;
    for (int i = 0; i < 3; ++i) {
      sys.a[i][i] += cl;
      sys.a[3 + i][3 + i] += ca;
      for (int j = 0; j < 3; ++j) {
        sys.a[i][3 + j] -= cl * s.m[i][j];
        sys.a[3 + i][j] -= cl * s.m[j][i];
        sys.a[3 + i][3 + j] += cl * sts.m[i][j];
      }
    }
    const Vec3 f0 = t.spring * c->linear_stiffness_n_per_m + d.linear_velocity * c->linear_damping_n_s_per_m;
    const Vec3 tau0 = cross(t.r, f0) + t.theta * c->angular_stiffness_nm_per_rad +
                      d.angular_velocity * c->angular_damping_nm_s_per_rad;
    for (int i = 0; i < 3; ++i) {
      sys.rhs[i] += dt * f0[i];
      sys.rhs[3 + i] += dt * tau0[i];
    }
  }
  return sys;
}

void integrate_body(RigidBody& body, std::vector<VirtualCoupling*>& couplings, const std::vector<DeviceState>& devices,
                    const Vec3& gravity, double dt) {
  const BodySystem sys = body_system(body, couplings, devices, gravity, dt);
  double u[6];
  solve6(sys.a, sys.rhs, u);
  const Vec3 v{u[0], u[1], u[2]}, w{u[3], u[4], u[5]};

  body.coupling_force = {};
  body.coupling_torque = {};
  for (VirtualCoupling* c : couplings) {
    const DeviceState& d = devices[c->device];
    const CouplingTerms t = coupling_terms(body, *c, d);
    const Vec3 grasp_velocity = v + cross(w, t.r);
    const Vec3 f = (t.spring - grasp_velocity * dt) * c->linear_stiffness_n_per_m +
                   (d.linear_velocity - grasp_velocity) * c->linear_damping_n_s_per_m;
    const Vec3 tau = (t.theta - w * dt) * c->angular_stiffness_nm_per_rad +
                     (d.angular_velocity - w) * c->angular_damping_nm_s_per_rad;
    c->device_force = -f;  // the device feels the opposite (line 9)
    c->device_torque = -tau;
    body.coupling_force += f;
    body.coupling_torque += cross(t.r, f) + tau;
  }

  // Leap-frog (line 8): velocities at t + dt/2, then positions and orientation at t + dt.
  const Mat3 inertia = body.world_inertia();
  body.linear_velocity = v;
  body.angular_velocity = w;
  body.angular_momentum = inertia * w;
  body.position += v * dt;
  body.orientation = normalized(rotation_from_vector(w * dt) * body.orientation);
  // Angular velocity for the new orientation from the conserved angular momentum (eq. 13 with
  // the inertia tensor rotated to the new pose: free rotation keeps L, not w).
  body.angular_velocity = body.world_inverse_inertia() * body.angular_momentum;
}

}  // namespace hapfluid::sim
