#version 450
#extension GL_GOOGLE_include_directive : require
// Eq. 2 over fluid neighbours plus the boundary term rho0 V_b W of wall and body particles
// (Akinci et al. 2012), then eq. 7 with negative pressures clamped to zero (a free surface must
// not pull particles together). Mirrors CpuSolver::compute_density: per-run partial sums of
// d^3 with d = max(h^2 - r^2, 0), the poly6 constant applied once at the end.
#include "common.glsl"
layout(local_size_x = 64) in;
layout(binding = BINDING_T_S_POS) uniform samplerBuffer s_pos;
layout(binding = BINDING_T_CELL_START) uniform usamplerBuffer cell_start;
layout(binding = BINDING_T_W_A) uniform samplerBuffer w_a;
layout(binding = BINDING_T_W_CELL_START) uniform usamplerBuffer w_cell_start;
layout(binding = BINDING_T_V_A) uniform samplerBuffer v_a;
layout(binding = BINDING_T_V_CELL_START) uniform usamplerBuffer v_cell_start;
layout(std430, binding = BINDING_S_DENSITY) writeonly buffer Density { vec4 density[]; };

float cube_sum(vec3 xi, samplerBuffer positions, uint b, uint e, bool weighted) {
  float sum = 0.0;
  for (uint j = b; j < e; ++j) {
    vec4 pj = texelFetch(positions, int(j));
    float dx = xi.x - pj.x, dy = xi.y - pj.y, dz = xi.z - pj.z;
    float d = h2() - (dx * dx + dy * dy + dz * dz);
    d = d > 0.0 ? d : 0.0;
    sum += weighted ? pj.w * d * d * d : d * d * d;
  }
  return sum;
}

void main() {
  uint i = gl_GlobalInvocationID.x;
  if (i >= P.counts.x) return;
  vec3 xi = texelFetch(s_pos, int(i)).xyz;
  float fluid_sum = 0.0, solid_sum = 0.0;
  { NEIGHBOUR_RUNS(cell_start, xi) fluid_sum += cube_sum(xi, s_pos, run_begin, run_end, false); }
  if (P.counts.y > 0u) { NEIGHBOUR_RUNS(w_cell_start, xi) solid_sum += cube_sum(xi, w_a, run_begin, run_end, true); }
  if (P.counts.z > 0u) { NEIGHBOUR_RUNS(v_cell_start, xi) solid_sum += cube_sum(xi, v_a, run_begin, run_end, true); }
  float mass = P.material.y, rho0 = P.material.z;
  float rho = P.kernel.z * (mass * fluid_sum + rho0 * solid_sum);
  float pressure = P.material.w * (rho - rho0);
  density[i] = vec4(rho, pressure > 0.0 ? pressure : 0.0, mass / rho, 0.0);
}
