#version 450
#extension GL_GOOGLE_include_directive : require
// Forces on fluid particles (Algorithm 1, lines 4-12) per cell (cell_group.glsl), as
// acceleration a = f / m = sum / rho:
//   pressure (eq. 5):        -(V_p / c_p) sum_i (V_i / c_i) (P_p + P_i) grad W
//   viscosity (eqs. 6, 9):    V_p sum_i V_i (mu_p + mu_i) / 2 (v_i - v_p) lap W
// with the first-moment volume correction 1 / c (density.w, gradient_correction.hpp). Wall and
// body particles keep their volumes (c = 1) and take the fluid particle's own pressure
// (pressure mirroring, Akinci et al. 2012). The terms of CpuSolver::compute_fluid_forces, per particle in the same order
// (fluid runs, walls, bodies; candidate by candidate), with each neighbour's data fetched once
// for all particles of the cell; velocity and density only when one of them is in range.
#include "common.glsl"
#include "cell_group.glsl"
layout(binding = BINDING_T_S_POS) uniform samplerBuffer s_pos;
layout(binding = BINDING_T_S_VEL) uniform samplerBuffer s_vel;
layout(binding = BINDING_T_S_DENSITY) uniform samplerBuffer s_density;
layout(binding = BINDING_T_CELL_START) uniform usamplerBuffer cell_start;
layout(binding = BINDING_T_W_A) uniform samplerBuffer w_a;
layout(binding = BINDING_T_W_B) uniform samplerBuffer w_b;
layout(binding = BINDING_T_W_C) uniform samplerBuffer w_c;
layout(binding = BINDING_T_W_CELL_START) uniform usamplerBuffer w_cell_start;
layout(binding = BINDING_T_V_A) uniform samplerBuffer v_a;
layout(binding = BINDING_T_V_B) uniform samplerBuffer v_b;
layout(binding = BINDING_T_V_CELL_START) uniform usamplerBuffer v_cell_start;
layout(std430, binding = BINDING_S_ACC) writeonly buffer Acc { vec4 acc[]; };

vec3 xs[CELL_GROUP], vs[CELL_GROUP], as[CELL_GROUP];
float ps[CELL_GROUP], vcs[CELL_GROUP], mus[CELL_GROUP];

void fluid_run(uint b, uint e) {
  for (uint j = b; j < e; ++j) {
    vec4 pj = texelFetch(s_pos, int(j));
    bool any_inside = false;
    [[unroll]] for (int s = 0; s < CELL_GROUP; ++s) {
      float dx = xs[s].x - pj.x, dy = xs[s].y - pj.y, dz = xs[s].z - pj.z;
      float r2 = dx * dx + dy * dy + dz * dz;
      any_inside = any_inside || (r2 < h2() && r2 > 0.0);
    }
    if (!any_inside) continue;
    vec4 vj = texelFetch(s_vel, int(j));
    vec4 dj = texelFetch(s_density, int(j));
    [[unroll]] for (int s = 0; s < CELL_GROUP; ++s) {
      float dx = xs[s].x - pj.x, dy = xs[s].y - pj.y, dz = xs[s].z - pj.z;
      float r2 = dx * dx + dy * dy + dz * dz;
      if (r2 >= h2() || r2 <= 0.0) continue;
      float r = sqrt(r2);
      float hr = h() - r;
      float pterm = -dj.z * (ps[s] + dj.y) * (vcs[s] * dj.w) * P.kernel.w * hr * hr / r;
      float vterm = dj.z * 0.5 * (mus[s] + pj.w) * P.material.x * hr;
      as[s].x += pterm * dx + vterm * (vj.x - vs[s].x);
      as[s].y += pterm * dy + vterm * (vj.y - vs[s].y);
      as[s].z += pterm * dz + vterm * (vj.z - vs[s].z);
    }
  }
}

// Walls and bodies: pressure mirrored; viscosity on the full relative velocity for bodies
// (no_slip = 1) and on its component along the pair direction for walls (no_slip = 0).
void solid_run(samplerBuffer sa, samplerBuffer sb, bool have_c, samplerBuffer sc, uint b, uint e) {
  for (uint j = b; j < e; ++j) {
    vec4 pj = texelFetch(sa, int(j));
    bool any_inside = false;
    [[unroll]] for (int s = 0; s < CELL_GROUP; ++s) {
      float dx = xs[s].x - pj.x, dy = xs[s].y - pj.y, dz = xs[s].z - pj.z;
      float r2 = dx * dx + dy * dy + dz * dz;
      any_inside = any_inside || (r2 < h2() && r2 > 0.0);
    }
    if (!any_inside) continue;
    vec4 vj = texelFetch(sb, int(j));
    float ns = have_c ? texelFetch(sc, int(j)).x : 1.0;
    [[unroll]] for (int s = 0; s < CELL_GROUP; ++s) {
      float dx = xs[s].x - pj.x, dy = xs[s].y - pj.y, dz = xs[s].z - pj.z;
      float r2 = dx * dx + dy * dy + dz * dz;
      if (r2 >= h2() || r2 <= 0.0) continue;
      float r = sqrt(r2);
      float hr = h() - r;
      float pterm = -pj.w * (2.0 * ps[s] * vcs[s]) * P.kernel.w * hr * hr / r;
      float vterm = pj.w * 0.5 * (mus[s] + vj.w) * P.material.x * hr;
      float dvx = vj.x - vs[s].x, dvy = vj.y - vs[s].y, dvz = vj.z - vs[s].z;
      float along = (1.0 - ns) * (dvx * dx + dvy * dy + dvz * dz) / r2;
      as[s].x += pterm * dx + vterm * (ns * dvx + along * dx);
      as[s].y += pterm * dy + vterm * (ns * dvy + along * dy);
      as[s].z += pterm * dz + vterm * (ns * dvz + along * dz);
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
    float inv_rho[CELL_GROUP];
    [[unroll]] for (int s = 0; s < CELL_GROUP; ++s) {
      bool used = uint(s) < n;
      int i = int(first) + (used ? s : 0);
      vec4 p4 = texelFetch(s_pos, i);
      vec4 d4 = texelFetch(s_density, i);
      // Slots past the cell's particles sit far away: nothing is inside their support.
      xs[s] = used ? p4.xyz : vec3(1e18);
      mus[s] = p4.w;
      vs[s] = texelFetch(s_vel, i).xyz;
      ps[s] = d4.y;
      vcs[s] = d4.w;
      inv_rho[s] = 1.0 / d4.x;
      as[s] = vec3(0.0);
    }
    for (int k = 0; k < 9; ++k) {
      if (!runs.valid[k]) continue;
      uint b = texelFetch(cell_start, runs.row[k] + runs.x0).x, e = texelFetch(cell_start, runs.row[k] + runs.x1 + 1).x;
      fluid_run(b, e);
    }
    if (P.counts.y > 0u)
      for (int k = 0; k < 9; ++k) {
        if (!runs.valid[k]) continue;
        uint b = texelFetch(w_cell_start, runs.row[k] + runs.x0).x, e = texelFetch(w_cell_start, runs.row[k] + runs.x1 + 1).x;
        solid_run(w_a, w_b, true, w_c, b, e);
      }
    if (P.counts.z > 0u)
      for (int k = 0; k < 9; ++k) {
        if (!runs.valid[k]) continue;
        uint b = texelFetch(v_cell_start, runs.row[k] + runs.x0).x, e = texelFetch(v_cell_start, runs.row[k] + runs.x1 + 1).x;
        solid_run(v_a, v_b, false, w_c, b, e);
      }
    [[unroll]] for (int s = 0; s < CELL_GROUP; ++s) {
      if (uint(s) >= n) break;
      acc[first + uint(s)] = vec4(as[s].x * inv_rho[s] + P.gravity_dt.x, as[s].y * inv_rho[s] + P.gravity_dt.y,
                                  as[s].z * inv_rho[s] + P.gravity_dt.z, 0.0);
    }
  }
}
