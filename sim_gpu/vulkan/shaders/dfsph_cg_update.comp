#version 450
#extension GL_GOOGLE_include_directive : require
// Conjugate gradients, 2 of 3: v += alpha p, r -= alpha A p, z = M^-1 r (into slot 4);
// partials: |r|^2 and r . z.
#include "dfsph_common.glsl"
layout(std430, binding = BINDING_S_VEL) buffer SVel { vec4 s_vel[]; };

void main() {
  uint k = gl_GlobalInvocationID.x;
  vec4 partial = vec4(0.0);
  if (k < P.counts.x) {
    float alpha = solve_float(SOLVE_CG_ALPHA);
    s_vel[k] = vec4(s_vel[k].xyz + alpha * D_VISC(k, 3u).xyz, 0.0);
    vec3 r = D_VISC(k, 2u).xyz - alpha * D_VISC(k, 4u).xyz;
    vec3 z = D_VISC(k, 1u).xyz * r;
    D_VISC(k, 2u) = vec4(r, 0.0);
    D_VISC(k, 4u) = vec4(z, 0.0);
    partial = vec4(dot(r, r), dot(r, z), 0.0, 0.0);
  }
  write_group_partial(partial);
}
