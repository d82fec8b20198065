#include "hapfluid/sim/rigid_body.hpp"

#include <cmath>

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

namespace {

// Solves A x = b for a 6x6 system by Gaussian elimination with partial pivoting (A is SPD here).
void solve6(double a[6][6], double b[6], double x[6]) {
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

// Cross-product matrix [r]x, so that [r]x w = r x w.
Mat3 skew(const Vec3& r) {
  Mat3 s;
  s.m[0][1] = -r.z; s.m[0][2] = r.y;
  s.m[1][0] = r.z;  s.m[1][2] = -r.x;
  s.m[2][0] = -r.y; s.m[2][1] = r.x;
  return s;
}

}  // namespace

void integrate_body(RigidBody& body, std::vector<VirtualCoupling*>& couplings, const std::vector<DeviceState>& devices,
                    const Vec3& gravity, double dt) {
  // Generalised velocity u = (v, w) at t - dt/2; mass matrix diag(m 1, I_world).
  const Mat3 inertia = body.world_inertia();
  const Vec3 force = body.fluid_force + body.contact_force + gravity * body.mass_kg;  // Algorithm 2, line 6
  const Vec3 torque = body.fluid_torque + body.contact_torque;
  double a[6][6] = {};
  double rhs[6];
  for (int i = 0; i < 3; ++i) {
    a[i][i] = body.mass_kg;
    for (int j = 0; j < 3; ++j) a[3 + i][3 + j] = inertia.m[i][j];
  }
  const Vec3 momentum = body.linear_velocity * body.mass_kg;
  const Vec3 angular = inertia * body.angular_velocity;
  for (int i = 0; i < 3; ++i) {
    rhs[i] = momentum[i] + dt * force[i];
    rhs[3 + i] = angular[i] + dt * torque[i];
  }
  // Couplings (line 7). Linear spring-damper at the grasp point p: velocity J u = v + w x r with
  // J = [1, -[r]x]; generalised force J^T F = (F, r x F). Implicit in u(t + dt/2):
  // F = k (x_d - p - dt J u') + b (v_d - J u'), tau = k_a (theta - dt w') + b_a (w_d - w').
  struct Terms { Vec3 r, spring, theta; double kl, bl, ka, ba; };
  std::vector<Terms> terms;
  terms.reserve(couplings.size());
  const Mat3 rot = body.rotation();
  for (VirtualCoupling* c : couplings) {
    const DeviceState& d = devices[c->device];
    Terms t;
    const Vec3 grasp_world = body.position + rot * (c->grasp_position - body.com_in_mesh_frame);
    t.r = grasp_world - body.position;
    t.spring = d.position - grasp_world;
    const Quat grasp_orientation = normalized(body.orientation * c->grasp_orientation);
    t.theta = rotation_vector(d.orientation * conjugate(grasp_orientation));
    t.kl = c->linear_stiffness_n_per_m;
    t.bl = c->linear_damping_n_s_per_m;
    t.ka = c->angular_stiffness_nm_per_rad;
    t.ba = c->angular_damping_nm_s_per_rad;
    const double cl = dt * (t.bl + dt * t.kl), ca = dt * (t.ba + dt * t.ka);
    // J^T J = [[1, -S], [S^T, S^T S]] with S = [r]x (S^T = -S).
    const Mat3 s = skew(t.r);
    const Mat3 sts = transpose(s) * s;
    for (int i = 0; i < 3; ++i) {
      a[i][i] += cl;
      a[3 + i][3 + i] += ca;
      for (int j = 0; j < 3; ++j) {
        a[i][3 + j] -= cl * s.m[i][j];
        a[3 + i][j] -= cl * s.m[j][i];
        a[3 + i][3 + j] += cl * sts.m[i][j];
      }
    }
    const Vec3 f0 = t.spring * t.kl + d.linear_velocity * t.bl;
    const Vec3 tau0 = cross(t.r, f0) + t.theta * t.ka + d.angular_velocity * t.ba;
    for (int i = 0; i < 3; ++i) {
      rhs[i] += dt * f0[i];
      rhs[3 + i] += dt * tau0[i];
    }
    terms.push_back(t);
  }
  double u[6];
  solve6(a, rhs, u);
  const Vec3 v{u[0], u[1], u[2]}, w{u[3], u[4], u[5]};

  body.coupling_force = {};
  body.coupling_torque = {};
  for (std::size_t k = 0; k < couplings.size(); ++k) {
    const Terms& t = terms[k];
    const DeviceState& d = devices[couplings[k]->device];
    const Vec3 grasp_velocity = v + cross(w, t.r);
    const Vec3 f = (t.spring - grasp_velocity * dt) * t.kl + (d.linear_velocity - grasp_velocity) * t.bl;
    const Vec3 tau = (t.theta - w * dt) * t.ka + (d.angular_velocity - w) * t.ba;
    couplings[k]->device_force = -f;  // the device feels the opposite (line 9)
    couplings[k]->device_torque = -tau;
    body.coupling_force += f;
    body.coupling_torque += cross(t.r, f) + tau;
  }

  // Leap-frog (line 8): velocities at t + dt/2, then positions and orientation at t + dt.
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
