#version 450
#extension GL_GOOGLE_include_directive : require
// The first pass of the viscosity solve (viscosity_rhs) on the start velocity v0 (S_VEL):
// b = v* - dt sum_solids c (v_b . x) / d grad, the walls' share of the diagonal, the Jacobi
// preconditioner, r = b - K v0 and p = M^-1 r. Partials: r . p, b . b and the largest diagonal
// excess, which bounds dt L's spectrum for the choice of an explicit step.
#include "dfsph_common.glsl"
layout(std430, binding = BINDING_S_VEL) readonly buffer SVel { vec4 s_vel[]; };
layout(binding = BINDING_T_S_POS) uniform samplerBuffer t_pos;
layout(binding = BINDING_T_W_A) uniform samplerBuffer w_a;
layout(binding = BINDING_T_W_B) uniform samplerBuffer w_b;
layout(binding = BINDING_T_W_CELL_START) uniform usamplerBuffer w_cell_start;

void main() {
  uint k = gl_GlobalInvocationID.x;
  vec4 partial = vec4(0.0);
  if (k < P.counts.x) {
    vec4 pi = texelFetch(t_pos, int(k));
    vec3 vi = s_vel[k].xyz;
    float mui = pi.w, rhoi = D_FIELD(k).x;
    float h2_ = P.dfsph_kernel.x, eps2 = P.dfsph_b.z, scale = viscosity_scale();
    vec3 diagonal = vec3(0.0), product = vec3(0.0), b = D_VISC(k, 0u).xyz;
    FOR_EACH_LISTED(k) {
      LISTED_PAIR;
      uint j = LISTED_INDEX;
      vec4 pj = texelFetch(t_pos, int(j));
      vec3 dx = pi.xyz - pj.xyz;
      vec3 g = LISTED_GRADIENT;
      float c = 2.0 * scale * (mui + pj.w) / ((rhoi + T_FIELD(j).x) * (dot(dx, dx) + eps2));
      diagonal -= c * dx * g;
      product += c * dot(vi - texelFetch(t_vel, int(j)).xyz, dx) * g;
    }
    if (P.counts.y > 0u) {
      NEIGHBOUR_RUNS(w_cell_start, pi) {
        for (uint j = run_begin; j < run_end; ++j) {
          vec4 s = texelFetch(w_a, int(j));
          vec3 d = pi.xyz - s.xyz;
          float r2 = dot(d, d);
          if (r2 < h2_) {
            vec4 sv = texelFetch(w_b, int(j));
            vec3 g = pair_term(d, s.w).xyz;
            float c = scale * (mui + sv.w) / (r2 + eps2);
            b -= c * dot(sv.xyz, d) * g;
            diagonal -= c * d * g;
            product += c * dot(vi, d) * g;
          }
        }
      }
    }
    vec3 wall = scale * (mui + P.dfsph_b.y) * wall_friction(pi.xyz);
    vec3 inv_diag = 1.0 / (vec3(1.0) + diagonal + wall);
    vec3 kv = vi - product + wall * vi;
    vec3 r = b - kv;
    vec3 z = inv_diag * r;
    D_VISC(k, 0u) = vec4(b, 0.0);
    D_VISC(k, 1u) = vec4(inv_diag, 0.0);
    D_VISC(k, 2u) = vec4(r, 0.0);
    D_VISC(k, 3u) = vec4(z, 0.0);
    D_VISC(k, 5u) = vec4(wall, 0.0);
    float excess = 1.0 / inv_diag.x + 1.0 / inv_diag.y + 1.0 / inv_diag.z - 3.0;
    partial = vec4(dot(r, z), dot(b, b), 0.0, excess);
  }
  write_group_partial(partial);
}
