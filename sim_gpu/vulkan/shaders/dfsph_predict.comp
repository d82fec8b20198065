#version 450
#extension GL_GOOGLE_include_directive : require
// v* = v + dt a, the viscosity solve's right-hand side; its iterate starts from v* plus the
// change its last solve made (Weiler et al. 2018's warm start; zero after an explicit step).
#include "dfsph_common.glsl"
layout(std430, binding = BINDING_S_VEL) buffer SVel { vec4 s_vel[]; };
layout(std430, binding = BINDING_S_ACC) readonly buffer SAcc { vec4 s_acc[]; };

void main() {
  uint k = gl_GlobalInvocationID.x;
  if (k >= P.counts.x) return;
  vec3 v = s_vel[k].xyz + P.gravity_dt.w * s_acc[k].xyz;
  D_VISC(k, 0u) = vec4(v, 0.0);
  v += D_DV_S(k).xyz;
  D_VISC(k, 6u) = vec4(v, 0.0);
  s_vel[k] = vec4(v, 0.0);
}
