#version 450
#extension GL_GOOGLE_include_directive : require
// The inputs of the CFL bound (CpuSolver::stable_time_step): the largest squared speed of
// fluid and body particles and the largest squared fluid acceleration. Pass 1 of 2: one
// partial maximum per workgroup. Squared magnitudes are non-negative, so their float bits
// order like unsigned integers and max is exact (no float atomics, any order gives one result).
#include "common.glsl"
layout(local_size_x = 256) in;
layout(std430, binding = BINDING_F_VEL) readonly buffer FVel { vec4 f_vel[]; };
layout(std430, binding = BINDING_S_ACC) readonly buffer SAcc { vec4 s_acc[]; };
layout(std430, binding = BINDING_B_VEL) readonly buffer BVel { vec4 b_vel[]; };
layout(std430, binding = BINDING_REDUCE) buffer Reduce { uint reduce[]; };
shared uint speed[256];
shared uint accel[256];

void main() {
  uint t = gl_LocalInvocationID.x;
  uint i = gl_GlobalInvocationID.x;
  float v2 = 0.0, a2 = 0.0;
  if (i < P.counts.x) {
    vec4 v = f_vel[i];
    vec4 a = s_acc[i];
    v2 = v.x * v.x + v.y * v.y + v.z * v.z;
    a2 = a.x * a.x + a.y * a.y + a.z * a.z;
  } else if (i < P.counts.x + P.counts.z) {
    vec4 v = b_vel[i - P.counts.x];
    v2 = v.x * v.x + v.y * v.y + v.z * v.z;
  }
  speed[t] = floatBitsToUint(v2);
  accel[t] = floatBitsToUint(a2);
  barrier();
  for (uint s = 128u; s > 0u; s >>= 1) {
    if (t < s) {
      speed[t] = max(speed[t], speed[t + s]);
      accel[t] = max(accel[t], accel[t + s]);
    }
    barrier();
  }
  if (t == 0u) {
    reduce[4u + 2u * gl_WorkGroupID.x] = speed[0];
    reduce[5u + 2u * gl_WorkGroupID.x] = accel[0];
  }
}
