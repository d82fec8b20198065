#version 450
#extension GL_GOOGLE_include_directive : require
// One error pass of a pressure solve (DfsphSolver::solve): the density rate
// s_i = sum_j V_j grad W_ij . (v_i - v_j) + v_i . (the solids' gradient sum), the particle's
// error (divergence: dt s where its neighbourhood is full and it compresses; density: the
// predicted excess rho/rho0 - 1 + dt s, at least 0) and its stiffness increment: on the first
// pass half of last step's stiffness where it compresses (warm start), then error * factor / dt^2.
// Partials: the errors' sum per workgroup. The first pass also opens the solve's state.
#include "dfsph_common.glsl"
layout(push_constant) uniform Push { uint mode; uint pad0, pad1, pad2; } pc;  // 0/1 divergence warm/iterate, 2/3 density
layout(std430, binding = BINDING_S_VEL) readonly buffer SVel { vec4 s_vel[]; };
layout(std430, binding = BINDING_D_KAPPA) writeonly buffer Kappa { float kappa[]; };

void main() {
  uint k = gl_GlobalInvocationID.x;
  bool density = pc.mode >= 2u, warm_start = pc.mode == 0u || pc.mode == 2u;
  float dt = P.gravity_dt.w;
  if (k == 0u && warm_start) {
    solve[SOLVE_GROUPS] = fluid_groups();
    solve[SOLVE_GROUPS + 1u] = 1u;
    solve[SOLVE_GROUPS + 2u] = 1u;
    solve[SOLVE_DONE] = 0u;
    solve[SOLVE_CONVERGED] = 0u;
    solve[SOLVE_ITERATIONS] = 0u;
  }
  float error = 0.0;
  if (k < P.counts.x) {
    vec3 vi = s_vel[k].xyz;
    vec3 s = vec3(0.0);
    FOR_EACH_LISTED(k) {
      LISTED_PAIR;
      s += LISTED_GRADIENT * (vi - texelFetch(t_vel, int(LISTED_INDEX)).xyz);
    }
    vec4 f = D_FIELD(k);
    float rate = s.x + s.y + s.z + dot(vi, D_SOLID(k).xyz);
    if (density) {
      float excess = f.x - 1.0 + dt * rate;
      error = excess > 0.0 ? excess : 0.0;
    } else {
      error = f.z >= P.dfsph_b.x && rate > 0.0 ? rate * dt : 0.0;
    }
    vec4 st = D_STIFF(k);
    float increment;
    if (warm_start) {
      float last = density ? D_WARM_S(k).x / (dt * dt) : D_WARM_S(k).y / dt;
      increment = error > 0.0 ? 0.5 * last : 0.0;
      if (density) st.y = increment; else st.z = increment;
    } else {
      increment = error * f.y / (dt * dt);
      if (density) st.y += increment; else st.z += increment;
    }
    st.x = increment;
    D_STIFF(k) = st;
    kappa[k] = increment;
  }
  write_group_partial(vec4(error, 0.0, 0.0, 0.0));
}
