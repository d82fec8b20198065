#version 450
#extension GL_GOOGLE_include_directive : require
// Conjugate gradients, 3 of 3: p = z + beta p.
#include "dfsph_common.glsl"

void main() {
  uint k = gl_GlobalInvocationID.x;
  if (k >= P.counts.x) return;
  D_VISC(k, 3u) = vec4(D_VISC(k, 4u).xyz + solve_float(SOLVE_CG_BETA) * D_VISC(k, 3u).xyz, 0.0);
}
