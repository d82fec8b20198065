#version 450
#extension GL_GOOGLE_include_directive : require
// The solver's per-particle memory into this step's cell order, as gather_fluid does for the
// particles: the warm starts of both pressure solves and of the viscosity solve.
#include "dfsph_common.glsl"
layout(std430, binding = BINDING_ORDER) readonly buffer Order { uint order[]; };

void main() {
  uint k = gl_GlobalInvocationID.x;
  if (k >= P.counts.x) return;
  uint i = order[k];
  D_WARM_S(k) = D_WARM_F(i);
  D_DV_S(k) = D_DV_F(i);
}
