#version 450
#extension GL_GOOGLE_include_directive : require
// Non-pressure accelerations (non_pressure_accelerations): gravity and the scene's XSPH
// fraction over dt, sum_j -(V_j W_ij / (rho_j / rho0)) (v_i - v_j).
#include "dfsph_common.glsl"
layout(std430, binding = BINDING_S_VEL) readonly buffer SVel { vec4 s_vel[]; };
layout(std430, binding = BINDING_S_ACC) writeonly buffer SAcc { vec4 s_acc[]; };
layout(binding = BINDING_T_S_POS) uniform samplerBuffer t_pos;

void main() {
  uint k = gl_GlobalInvocationID.x;
  if (k >= P.counts.x) return;
  float xsph = P.dfsph_a.w / P.gravity_dt.w;
  vec3 s = vec3(0.0);
  if (xsph > 0.0) {
    vec3 vi = s_vel[k].xyz, pi = texelFetch(t_pos, int(k)).xyz;
    FOR_EACH_LISTED(k) {
      LISTED_PAIR;
      uint j = LISTED_INDEX;
      float vw = pair_term(pi - texelFetch(t_pos, int(j)).xyz, P.dfsph_a.x).w;  // as the density pass listed it
      s -= (vw / T_FIELD(j).x) * (vi - texelFetch(t_vel, int(j)).xyz);
    }
  }
  s_acc[k] = vec4(P.gravity_dt.xyz + xsph * s, 0.0);
}
