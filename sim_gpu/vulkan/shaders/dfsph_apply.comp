#version 450
#extension GL_GOOGLE_include_directive : require
// The velocity change of this iteration's stiffness increments k (apply_stiffness):
// v_i -= dt (k_i sum_solids V grad W + sum_fluid (k_i + k_j) V_j grad W_ij).
#include "dfsph_common.glsl"
layout(std430, binding = BINDING_S_VEL) buffer SVel { vec4 s_vel[]; };

void main() {
  uint k = gl_GlobalInvocationID.x;
  if (k >= P.counts.x) return;
  float ki = D_STIFF(k).x;
  vec3 a = ki * D_SOLID(k).xyz;
  FOR_EACH_LISTED(k) {
    LISTED_PAIR;
    a += (ki + texelFetch(t_kappa, int(LISTED_INDEX)).x) * LISTED_GRADIENT;
  }
  s_vel[k] = vec4(s_vel[k].xyz - P.gravity_dt.w * a, 0.0);
}
