#version 450
#extension GL_GOOGLE_include_directive : require
// Density (eqs. 2, 7) per cell (cell_group.glsl): the sums of CpuSolver::compute_density per
// particle and in the same order (per-run partial sums of d^3, d = max(h^2 - r^2, 0), over
// fluid, then walls and bodies weighted by their Akinci volume V_b), with each neighbour
// fetched once for all particles of the cell. Eq. 7 with negative pressures clamped to zero:
// a free surface must not pull particles together. Alongside, the sums of the first-moment
// kernel's shape (h - r)^2 r that give the volume correction 1 / c of the pressure force
// (sim_gpu/include/hapfluid/sim/gradient_correction.hpp), stored in density.w.
#include "common.glsl"
#include "cell_group.glsl"
layout(binding = BINDING_T_S_POS) uniform samplerBuffer s_pos;
layout(binding = BINDING_T_CELL_START) uniform usamplerBuffer cell_start;
layout(binding = BINDING_T_W_A) uniform samplerBuffer w_a;
layout(binding = BINDING_T_W_CELL_START) uniform usamplerBuffer w_cell_start;
layout(binding = BINDING_T_V_A) uniform samplerBuffer v_a;
layout(binding = BINDING_T_V_CELL_START) uniform usamplerBuffer v_cell_start;
layout(std430, binding = BINDING_S_DENSITY) writeonly buffer Density { vec4 density[]; };

vec3 xs[CELL_GROUP];
float run_sum[CELL_GROUP], run_moment[CELL_GROUP];

void accumulate_run(samplerBuffer positions, uint b, uint e, bool weighted) {
  [[unroll]] for (int s = 0; s < CELL_GROUP; ++s) run_sum[s] = 0.0, run_moment[s] = 0.0;
  for (uint j = b; j < e; ++j) {
    vec4 pj = texelFetch(positions, int(j));
    [[unroll]] for (int s = 0; s < CELL_GROUP; ++s) {
      float dx = xs[s].x - pj.x, dy = xs[s].y - pj.y, dz = xs[s].z - pj.z;
      float r2 = dx * dx + dy * dy + dz * dz;
      float d = h2() - r2;
      d = d > 0.0 ? d : 0.0;
      float r = sqrt(r2);
      float hr = h() - r > 0.0 ? h() - r : 0.0;
      float w = weighted ? pj.w : 1.0;
      run_sum[s] += w * d * d * d;
      run_moment[s] += w * hr * hr * r;
    }
  }
}

void main() {
  uint c = gl_GlobalInvocationID.x;
  if (c >= uint(P.grid_dims.w)) return;
  uint begin = texelFetch(cell_start, int(c)).x, end = texelFetch(cell_start, int(c) + 1).x;
  if (begin == end) return;
  CellRuns runs = cell_runs(c);
  for (uint first = begin; first < end; first += CELL_GROUP) {
    uint n = min(uint(CELL_GROUP), end - first);
    float fluid_sum[CELL_GROUP], solid_sum[CELL_GROUP], fluid_moment[CELL_GROUP], solid_moment[CELL_GROUP];
    [[unroll]] for (int s = 0; s < CELL_GROUP; ++s) {
      // Slots past the cell's particles sit far away: their sums are never written.
      xs[s] = uint(s) < n ? texelFetch(s_pos, int(first) + s).xyz : vec3(1e18);
      fluid_sum[s] = 0.0;
      solid_sum[s] = 0.0;
      fluid_moment[s] = 0.0;
      solid_moment[s] = 0.0;
    }
    for (int k = 0; k < 9; ++k) {
      if (!runs.valid[k]) continue;
      uint b = texelFetch(cell_start, runs.row[k] + runs.x0).x, e = texelFetch(cell_start, runs.row[k] + runs.x1 + 1).x;
      if (b >= e) continue;
      accumulate_run(s_pos, b, e, false);
      [[unroll]] for (int s = 0; s < CELL_GROUP; ++s) fluid_sum[s] += run_sum[s], fluid_moment[s] += run_moment[s];
    }
    if (P.counts.y > 0u)
      for (int k = 0; k < 9; ++k) {
        if (!runs.valid[k]) continue;
        uint b = texelFetch(w_cell_start, runs.row[k] + runs.x0).x, e = texelFetch(w_cell_start, runs.row[k] + runs.x1 + 1).x;
        if (b >= e) continue;
        accumulate_run(w_a, b, e, true);
        [[unroll]] for (int s = 0; s < CELL_GROUP; ++s) solid_sum[s] += run_sum[s], solid_moment[s] += run_moment[s];
      }
    if (P.counts.z > 0u)
      for (int k = 0; k < 9; ++k) {
        if (!runs.valid[k]) continue;
        uint b = texelFetch(v_cell_start, runs.row[k] + runs.x0).x, e = texelFetch(v_cell_start, runs.row[k] + runs.x1 + 1).x;
        if (b >= e) continue;
        accumulate_run(v_a, b, e, true);
        [[unroll]] for (int s = 0; s < CELL_GROUP; ++s) solid_sum[s] += run_sum[s], solid_moment[s] += run_moment[s];
      }
    float mass = P.material.y, rho0 = P.material.z;
    [[unroll]] for (int s = 0; s < CELL_GROUP; ++s) {
      if (uint(s) >= n) break;
      float rho = P.kernel.z * (mass * fluid_sum[s] + rho0 * solid_sum[s]);
      float pressure = P.material.w * (rho - rho0);
      float volume = mass / rho;
      float c = (-P.kernel.w / 3.0) * (volume * fluid_moment[s] + solid_moment[s]);
      c = clamp(c, P.corrections.x, P.corrections.y);
      density[first + uint(s)] = vec4(rho, pressure > 0.0 ? pressure : 0.0, volume, 1.0 / c);
    }
  }
}
