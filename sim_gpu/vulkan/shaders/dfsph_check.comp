#version 450
#extension GL_GOOGLE_include_directive : require
// After error pass `iteration` of a running pressure solve (one workgroup): the mean error from
// the partials; below the tolerance, once the solve has had its fewest iterations, the solve
// ends: the iterating passes that follow are dispatched with zero workgroups. The host is not
// asked: the whole solve runs in one submission.
#include "dfsph_common.glsl"
layout(push_constant) uniform Push { uint iteration; uint density; uint pad0, pad1; } pc;

void main() {
  if (solve[SOLVE_DONE] != 0u) return;
  float mean = total_of_partials().x / float(P.counts.x);
  if (gl_LocalInvocationID.x != 0u) return;
  set_solve_float(SOLVE_MEAN, mean);
  float tolerance = pc.density != 0u ? P.dfsph_a.y : P.dfsph_a.z;
  uint fewest = uint(pc.density != 0u ? P.dfsph_c.x : P.dfsph_c.y);
  if (pc.iteration >= fewest && mean <= tolerance) {
    solve[SOLVE_DONE] = 1u;
    solve[SOLVE_CONVERGED] = 1u;
    solve[SOLVE_ITERATIONS] = pc.iteration;
    solve[SOLVE_GROUPS] = 0u;
  }
}
