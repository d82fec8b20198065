#version 450
#extension GL_GOOGLE_include_directive : require
// Conjugate gradients on the viscosity system, 1 of 3 per iteration (viscosity_apply): A p =
// K p into slot 4; partials: p . A p.
#include "dfsph_common.glsl"
layout(binding = BINDING_T_S_POS) uniform samplerBuffer t_pos;
layout(binding = BINDING_T_W_A) uniform samplerBuffer w_a;
layout(binding = BINDING_T_W_B) uniform samplerBuffer w_b;
layout(binding = BINDING_T_W_CELL_START) uniform usamplerBuffer w_cell_start;

void main() {
  uint k = gl_GlobalInvocationID.x;
  vec4 partial = vec4(0.0);
  if (k < P.counts.x) {
    vec4 pi = texelFetch(t_pos, int(k));
    vec3 vi = D_VISC(k, 3u).xyz;
    float mui = pi.w, rhoi = D_FIELD(k).x;
    float h2_ = P.dfsph_kernel.x, eps2 = P.dfsph_b.z, scale = viscosity_scale();
    vec3 product = vec3(0.0);
    FOR_EACH_LISTED(k) {
      LISTED_PAIR;
      uint j = LISTED_INDEX;
      vec4 pj = texelFetch(t_pos, int(j));
      vec3 dx = pi.xyz - pj.xyz;
      float c = 2.0 * scale * (mui + pj.w) / ((rhoi + T_FIELD(j).x) * (dot(dx, dx) + eps2));
      product += c * dot(vi - T_VISC(j, 3u).xyz, dx) * LISTED_GRADIENT;
    }
    if (P.counts.y > 0u) {
      NEIGHBOUR_RUNS(w_cell_start, pi) {
        for (uint j = run_begin; j < run_end; ++j) {
          vec4 s = texelFetch(w_a, int(j));
          vec3 d = pi.xyz - s.xyz;
          float r2 = dot(d, d);
          if (r2 < h2_) {
            float c = scale * (mui + texelFetch(w_b, int(j)).w) / (r2 + eps2);
            product += c * dot(vi, d) * pair_term(d, s.w).xyz;
          }
        }
      }
    }
    vec3 ap = vi - product + D_VISC(k, 5u).xyz * vi;
    D_VISC(k, 4u) = vec4(ap, 0.0);
    partial.x = dot(vi, ap);
  }
  write_group_partial(partial);
}
