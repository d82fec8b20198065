#version 450
#extension GL_GOOGLE_include_directive : require
// The end of the viscosity solve: an explicit step adds r (the viscous change at the start
// velocity) and keeps no change for the next start; a solve keeps the change it made,
// v - v0, for the next one's start. Invocation 0 counts the CG iterations.
#include "dfsph_common.glsl"
layout(push_constant) uniform Push { uint budget; uint pad0, pad1, pad2; } pc;  // iterations recorded
layout(std430, binding = BINDING_S_VEL) buffer SVel { vec4 s_vel[]; };

void main() {
  uint k = gl_GlobalInvocationID.x;
  bool explicit_step = solve[SOLVE_EXPLICIT] != 0u;
  if (k < P.counts.x) {
    vec3 v = s_vel[k].xyz;
    if (explicit_step) {
      s_vel[k] = vec4(v + D_VISC(k, 2u).xyz, 0.0);
      D_DV_S(k) = vec4(0.0);
    } else {
      D_DV_S(k) = vec4(D_DV_S(k).xyz + v - D_VISC(k, 6u).xyz, 0.0);
    }
  }
  if (k == 0u && !explicit_step) {
    bool converged = solve[SOLVE_CONVERGED] != 0u;
    uint its = converged ? solve[SOLVE_ITERATIONS] : pc.budget;
    solve[SOLVE_VISCOSITY_ITS] += its;
    solve[SOLVE_MOST_VISCOSITY_ITS] = max(solve[SOLVE_MOST_VISCOSITY_ITS], its);
    if (!converged) solve[SOLVE_UNCONVERGED] += 1u;
    if (!converged && pc.budget < uint(P.dfsph_c.z)) solve[SOLVE_BUDGET_OVERRUNS] += 1u;
  }
}
