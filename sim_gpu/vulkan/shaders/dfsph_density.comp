#version 450
#extension GL_GOOGLE_include_directive : require
// Density and DFSPH factor (build_pairs): rho / rho0 = sum V_j W_ij over fluid and static solids
// plus the walls' share; the factor 1 / (|sum_j V_j grad W_ij|^2 + sum_fluid |V_j grad W_ij|^2);
// the solids' and walls' gradient sum; the neighbour counts; the list of fluid neighbours with
// their pair gradients. A list that would overflow is a fault the host reports.
#include "dfsph_common.glsl"
layout(std430, binding = BINDING_S_POS) readonly buffer SPos { vec4 s_pos[]; };
layout(binding = BINDING_T_CELL_START) uniform usamplerBuffer cell_start;
layout(binding = BINDING_T_S_POS) uniform samplerBuffer t_pos;
layout(binding = BINDING_T_W_A) uniform samplerBuffer w_a;
layout(binding = BINDING_T_W_CELL_START) uniform usamplerBuffer w_cell_start;
layout(std430, binding = BINDING_D_LIST) writeonly buffer List { vec4 list[]; };

void main() {
  uint k = gl_GlobalInvocationID.x;
  if (k >= P.counts.x) return;
  vec3 p = s_pos[k].xyz;
  float h2_ = P.dfsph_kernel.x, volume = P.dfsph_a.x;
  vec4 sf = vec4(0.0), ss = vec4(0.0);
  float g2 = 0.0;
  uint n = 0u, cap = list_capacity();
  {
    NEIGHBOUR_RUNS(cell_start, p) {
      for (uint j = run_begin; j < run_end; ++j) {
        vec3 d = p - texelFetch(t_pos, int(j)).xyz;
        if (dot(d, d) < h2_) {
          vec4 t = pair_term(d, volume);
          sf += t;
          g2 += dot(t.xyz, t.xyz);
          if (n < cap) list[listed_at(k, n)] = vec4(t.xyz, float(j));
          ++n;
        }
      }
    }
  }
  uint fluid = n;
  if (fluid > cap) atomicMax(solve[SOLVE_LIST_OVERFLOW], fluid);
  if (P.counts.y > 0u) {
    NEIGHBOUR_RUNS(w_cell_start, p) {
      for (uint j = run_begin; j < run_end; ++j) {
        vec4 s = texelFetch(w_a, int(j));
        vec3 d = p - s.xyz;
        if (dot(d, d) < h2_) {
          ss += pair_term(d, s.w);
          ++n;
        }
      }
    }
  }
  vec3 wall_gradient;
  float wall_share = wall_sample(p, wall_gradient);
  float density_hat = sf.w + ss.w + wall_share;
  vec3 s = ss.xyz + wall_gradient;
  vec3 t = sf.xyz + s;
  float denominator = dot(t, t) + g2;
  float tiny = 1e-6 / h2_;
  D_FIELD(k) = vec4(density_hat, denominator > tiny ? 1.0 / denominator : 0.0, float(min(n, 65535u)), float(fluid));
  D_SOLID(k) = vec4(s, 0.0);
}
