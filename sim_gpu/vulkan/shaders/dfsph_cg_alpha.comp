#version 450
#extension GL_GOOGLE_include_directive : require
// Conjugate gradients (one workgroup): alpha = r . z / p . A p; a solve whose p . A p is not
// positive has converged to round-off and ends.
#include "dfsph_common.glsl"
layout(push_constant) uniform Push { uint iteration; uint pad0, pad1, pad2; } pc;

void main() {
  if (solve[SOLVE_DONE] != 0u) return;
  float pap = total_of_partials().x;
  if (gl_LocalInvocationID.x != 0u) return;
  if (!(pap > 0.0)) {
    solve[SOLVE_DONE] = 1u;
    solve[SOLVE_CONVERGED] = 1u;
    solve[SOLVE_ITERATIONS] = pc.iteration;
    solve[SOLVE_GROUPS] = 0u;
    return;
  }
  set_solve_float(SOLVE_CG_ALPHA, solve_float(SOLVE_CG_RZ) / pap);
}
