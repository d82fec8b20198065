#version 450
#extension GL_GOOGLE_include_directive : require
// After the viscosity solve's first pass (one workgroup): a viscosity so low that one explicit
// step is as exact as the solve (DfsphSolver::viscosity_solve: dt L's largest eigenvalue,
// bounded by 2 sqrt(3) times the largest diagonal excess, squared within the solve's tolerance)
// takes that step and the conjugate-gradient passes are dispatched with zero workgroups;
// otherwise the solve opens with r . z and its stopping bound.
#include "dfsph_common.glsl"

const float kViscosityTolerance = 1e-3;

void main() {
  vec4 total = total_of_partials();
  if (gl_LocalInvocationID.x != 0u) return;
  float lambda = 2.0 * sqrt(3.0) * total.w;
  bool explicit_step = lambda * lambda <= kViscosityTolerance;
  solve[SOLVE_EXPLICIT] = explicit_step ? 1u : 0u;
  solve[SOLVE_DONE] = explicit_step ? 1u : 0u;
  solve[SOLVE_CONVERGED] = 0u;
  solve[SOLVE_ITERATIONS] = 0u;
  solve[SOLVE_GROUPS] = explicit_step ? 0u : fluid_groups();
  solve[SOLVE_GROUPS + 1u] = 1u;
  solve[SOLVE_GROUPS + 2u] = 1u;
  set_solve_float(SOLVE_MEAN, 0.0);
  set_solve_float(SOLVE_CG_RZ, total.x);
  set_solve_float(SOLVE_CG_LIMIT, kViscosityTolerance * kViscosityTolerance * total.y);
  if (explicit_step) solve[SOLVE_EXPLICIT_VISC] += 1u;
}
