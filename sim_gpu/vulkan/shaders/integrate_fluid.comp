#version 450
#extension GL_GOOGLE_include_directive : require
// Leap-frog (Algorithm 1, lines 13-16): v(t + dt/2) = v(t - dt/2) + a dt, x(t + dt) = x + v dt,
// written back to the persistent arrays in this step's cell order. Last resort, as on the CPU:
// a particle that reaches a wall's first particle layer (or leaves the box on an open side) is
// put back and counted.
#include "common.glsl"
layout(local_size_x = 64) in;
layout(std430, binding = BINDING_S_POS) readonly buffer SPos { vec4 s_pos[]; };
layout(std430, binding = BINDING_S_VEL) readonly buffer SVel { vec4 s_vel[]; };
layout(std430, binding = BINDING_S_ID) readonly buffer SId { uint s_id[]; };
layout(std430, binding = BINDING_S_ACC) readonly buffer SAcc { vec4 s_acc[]; };
layout(std430, binding = BINDING_F_POS) writeonly buffer FPos { vec4 f_pos[]; };
layout(std430, binding = BINDING_F_VEL) writeonly buffer FVel { vec4 f_vel[]; };
layout(std430, binding = BINDING_F_ID) writeonly buffer FId { uint f_id[]; };
layout(std430, binding = BINDING_REDUCE) buffer Reduce { uint reduce[]; };  // [0]: clamped count

void main() {
  uint k = gl_GlobalInvocationID.x;
  if (k >= P.counts.x) return;
  vec4 x = s_pos[k];
  vec4 v = s_vel[k];
  vec4 acc = s_acc[k];
  float dt = P.gravity_dt.w;
  bool out_of_box = false;
  for (int axis = 0; axis < 3; ++axis) {
    float vn = v[axis] + acc[axis] * dt;
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
  f_vel[k] = v;
  f_id[k] = s_id[k];
  if (out_of_box) atomicAdd(reduce[0], 1u);
}
