#version 450
#extension GL_GOOGLE_include_directive : require
// Contact pressure of body particles (CpuSolver::compute_body_contact_pressure): rigid
// particles keep a constant density (§4.1); what they get is k rho0 sum_c V_c W over particles
// of walls and of other bodies, so body<->body and body<->wall contacts push apart with the
// same pressure force as the fluid. One invocation per body-view particle; the result goes to
// the particle's unsorted slot.
#include "common.glsl"
layout(local_size_x = 64) in;
layout(binding = BINDING_T_W_A) uniform samplerBuffer w_a;
layout(binding = BINDING_T_W_CELL_START) uniform usamplerBuffer w_cell_start;
layout(binding = BINDING_T_V_A) uniform samplerBuffer v_a;
layout(binding = BINDING_T_V_C) uniform samplerBuffer v_c;
layout(binding = BINDING_T_V_CELL_START) uniform usamplerBuffer v_cell_start;
layout(std430, binding = BINDING_B_PRESSURE) writeonly buffer BPressure { float b_pressure[]; };

void main() {
  uint k = gl_GlobalInvocationID.x;
  if (k >= P.counts.z) return;
  vec3 xi = texelFetch(v_a, int(k)).xyz;
  vec4 ci = texelFetch(v_c, int(k));
  float own = ci.y;
  float sum = 0.0;
  if (P.counts.y > 0u) {
    NEIGHBOUR_RUNS(w_cell_start, xi) {
      float run = 0.0;
      for (uint j = run_begin; j < run_end; ++j) {
        vec4 pj = texelFetch(w_a, int(j));
        float dx = xi.x - pj.x, dy = xi.y - pj.y, dz = xi.z - pj.z;
        float d = h2() - (dx * dx + dy * dy + dz * dz);
        d = d > 0.0 ? d : 0.0;
        run += pj.w * d * d * d;
      }
      sum += run;
    }
  }
  // Other bodies' particles (body<->body contact); with a single dynamic body every candidate
  // would be its own and skipped: the loop is not run at all.
  if (P.counts.w > 1u) {
    NEIGHBOUR_RUNS(v_cell_start, xi) {
      for (uint j = run_begin; j < run_end; ++j) {
        if (texelFetch(v_c, int(j)).y == own) continue;
        vec4 pj = texelFetch(v_a, int(j));
        float dx = xi.x - pj.x, dy = xi.y - pj.y, dz = xi.z - pj.z;
        float d = h2() - (dx * dx + dy * dy + dz * dz);
        d = d > 0.0 ? d : 0.0;
        sum += pj.w * d * d * d;
      }
    }
  }
  b_pressure[uint(ci.z)] = P.material.w * P.material.z * P.kernel.z * sum;
}
