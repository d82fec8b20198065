#version 450
#extension GL_GOOGLE_include_directive : require
// The initial state (as DfsphSolver's constructor): this sort's cell order becomes the
// persistent order (adopt_sorted), with the solver's per-particle memory and the densities of
// the first frame.
#include "dfsph_common.glsl"
layout(std430, binding = BINDING_S_DENSITY) writeonly buffer SDensity { vec4 s_density[]; };

void main() {
  uint k = gl_GlobalInvocationID.x;
  if (k >= P.counts.x) return;
  D_WARM_F(k) = D_WARM_S(k);
  D_DV_F(k) = D_DV_S(k);
  float rho_hat = D_FIELD(k).x, rho0 = P.material.z;
  s_density[k] = vec4(rho_hat * rho0, 0.0, P.material.y / (rho_hat * rho0), 1.0);
}
