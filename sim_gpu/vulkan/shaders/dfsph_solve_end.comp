#version 450
#extension GL_GOOGLE_include_directive : require
// The end of a pressure solve (DfsphSolver::solve's last pass): a solve that converged takes
// back the increments of its last error pass (they were never applied); the step's total
// stiffness becomes next step's warm start. Invocation 0 counts the iterations (a solve that did
// not converge took all the iterations recorded).
#include "dfsph_common.glsl"
layout(push_constant) uniform Push { uint density; uint budget; uint pad0, pad1; } pc;  // budget: iterations recorded

void main() {
  uint k = gl_GlobalInvocationID.x;
  bool converged = solve[SOLVE_CONVERGED] != 0u;
  float dt = P.gravity_dt.w;
  if (k < P.counts.x) {
    vec4 st = D_STIFF(k);
    if (pc.density != 0u) {
      if (converged) st.y -= st.x;
      D_WARM_S(k).x = st.y * dt * dt;
    } else {
      if (converged) st.z -= st.x;
      D_WARM_S(k).y = st.z * dt;
    }
    D_STIFF(k) = st;
  }
  if (k == 0u) {
    uint its = converged ? solve[SOLVE_ITERATIONS] : pc.budget;
    if (!converged) solve[SOLVE_UNCONVERGED] += 1u;
    if (!converged && pc.budget < uint(P.dfsph_c.z)) solve[SOLVE_BUDGET_OVERRUNS] += 1u;
    if (pc.density != 0u) {
      solve[SOLVE_MOST_DENSITY_ITS] = max(solve[SOLVE_MOST_DENSITY_ITS], its);
      solve[SOLVE_DENSITY_ITS] += its;
      float mean = solve_float(SOLVE_MEAN);
      set_solve_float(SOLVE_LAST_DENSITY_ERROR, mean);
      solve[SOLVE_MAX_DENSITY_ERROR] = max(solve[SOLVE_MAX_DENSITY_ERROR], floatBitsToUint(max(mean, 0.0)));
    } else {
      solve[SOLVE_MOST_DIVERGENCE_ITS] = max(solve[SOLVE_MOST_DIVERGENCE_ITS], its);
      solve[SOLVE_DIVERGENCE_ITS] += its;
    }
  }
}
