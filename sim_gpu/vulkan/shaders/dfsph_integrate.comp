#version 450
#extension GL_GOOGLE_include_directive : require
// x(t + dt) = x + dt v(t + dt) (DfsphSolver::integrate_positions), written back to the persistent
// arrays in this step's cell order with the solver's per-particle memory; last resort, a
// particle that reaches a wall's boundary layer is put back and counted. While settling the
// fluid keeps only part of its velocity. Also the outputs: density, pressure
// p = k rho^2 / rho0 of the density solve (k = p / (rho rho0) in the normalised form), volume.
#include "dfsph_common.glsl"
layout(std430, binding = BINDING_S_POS) readonly buffer SPos { vec4 s_pos[]; };
layout(std430, binding = BINDING_S_VEL) readonly buffer SVel { vec4 s_vel[]; };
layout(std430, binding = BINDING_S_ID) readonly buffer SId { uint s_id[]; };
layout(std430, binding = BINDING_S_DENSITY) writeonly buffer SDensity { vec4 s_density[]; };
layout(std430, binding = BINDING_F_POS) writeonly buffer FPos { vec4 f_pos[]; };
layout(std430, binding = BINDING_F_VEL) writeonly buffer FVel { vec4 f_vel[]; };
layout(std430, binding = BINDING_F_ID) writeonly buffer FId { uint f_id[]; };
layout(std430, binding = BINDING_REDUCE) buffer Reduce { uint reduce[]; };  // [0]: clamped count

void main() {
  uint k = gl_GlobalInvocationID.x;
  if (k >= P.counts.x) return;
  vec4 x = s_pos[k];
  vec4 v = s_vel[k];
  float dt = P.gravity_dt.w;
  bool out_of_box = false;
  for (int axis = 0; axis < 3; ++axis) {
    float vn = v[axis];
    float xn = x[axis] + vn * dt;
    if (xn < P.clamp_lo[axis]) {
      xn = P.clamp_lo[axis]; vn = vn < 0.0 ? 0.0 : vn; out_of_box = true;
    } else if (xn > P.clamp_hi[axis]) {
      xn = P.clamp_hi[axis]; vn = vn > 0.0 ? 0.0 : vn; out_of_box = true;
    }
    v[axis] = vn;
    x[axis] = xn;
  }
  f_pos[k] = x;
  f_vel[k] = vec4(v.xyz * P.dfsph_b.w, 0.0);
  f_id[k] = s_id[k];
  D_WARM_F(k) = D_WARM_S(k);
  D_DV_F(k) = D_DV_S(k);
  float rho_hat = D_FIELD(k).x, rho0 = P.material.z;
  s_density[k] = vec4(rho_hat * rho0, D_STIFF(k).y * rho_hat * rho_hat * rho0, P.material.y / (rho_hat * rho0), 1.0);
  if (out_of_box) atomicAdd(reduce[0], 1u);
}
