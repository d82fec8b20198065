#version 450
#extension GL_GOOGLE_include_directive : require
// Conjugate gradients (one workgroup): the solve ends once |r|^2 is within its bound; else
// beta = (new r . z) / (old r . z).
#include "dfsph_common.glsl"
layout(push_constant) uniform Push { uint iteration; uint pad0, pad1, pad2; } pc;

void main() {
  if (solve[SOLVE_DONE] != 0u) return;
  vec4 total = total_of_partials();
  if (gl_LocalInvocationID.x != 0u) return;
  set_solve_float(SOLVE_MEAN, total.x);
  if (total.x <= solve_float(SOLVE_CG_LIMIT)) {
    solve[SOLVE_DONE] = 1u;
    solve[SOLVE_CONVERGED] = 1u;
    solve[SOLVE_ITERATIONS] = pc.iteration + 1u;
    solve[SOLVE_GROUPS] = 0u;
    return;
  }
  set_solve_float(SOLVE_CG_BETA, total.y / solve_float(SOLVE_CG_RZ));
  set_solve_float(SOLVE_CG_RZ, total.y);
}
