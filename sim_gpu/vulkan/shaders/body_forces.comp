#version 450
#extension GL_GOOGLE_include_directive : require
// Forces on dynamic body particles (CpuSolver::compute_body_particle_forces): from the fluid
// (f^haptic, eq. 8: the exact opposite of each pair term the fluid particle receives, so
// momentum is conserved; the body's viscosity enters eq. 9) and from other solids (contact:
// contact pressure, eq. 9 with both solids' viscosities, and the artificial viscosity of
// approaching pairs, contact_damping.hpp).
// One invocation per body particle in body order, so the per-body sums read contiguous ranges.
#include "common.glsl"
layout(local_size_x = 64) in;
layout(binding = BINDING_T_S_POS) uniform samplerBuffer s_pos;
layout(binding = BINDING_T_S_VEL) uniform samplerBuffer s_vel;
layout(binding = BINDING_T_S_DENSITY) uniform samplerBuffer s_density;
layout(binding = BINDING_T_CELL_START) uniform usamplerBuffer cell_start;
layout(binding = BINDING_T_W_A) uniform samplerBuffer w_a;
layout(binding = BINDING_T_W_B) uniform samplerBuffer w_b;
layout(binding = BINDING_T_W_CELL_START) uniform usamplerBuffer w_cell_start;
layout(binding = BINDING_T_V_A) uniform samplerBuffer v_a;
layout(binding = BINDING_T_V_B) uniform samplerBuffer v_b;
layout(binding = BINDING_T_V_C) uniform samplerBuffer v_c;
layout(binding = BINDING_T_V_CELL_START) uniform usamplerBuffer v_cell_start;
layout(std430, binding = BINDING_B_POS) readonly buffer BPos { vec4 b_pos[]; };
layout(std430, binding = BINDING_B_VEL) readonly buffer BVel { vec4 b_vel[]; };
layout(std430, binding = BINDING_B_REST) readonly buffer BRest { vec4 b_rest[]; };
layout(std430, binding = BINDING_B_PRESSURE) readonly buffer BPressure { float b_pressure[]; };
layout(std430, binding = BINDING_B_FORCE) writeonly buffer BForce { vec4 b_force[]; };
layout(std430, binding = BINDING_B_CONTACT) writeonly buffer BContact { vec4 b_contact[]; };

// contact_viscous_pressure of contact_damping.hpp: Monaghan's Pi_ij while the pair approaches
// (v_dot_r = (v_i - v_j) . (x_i - x_j) < 0), Pa.
float contact_viscous_pressure(float v_dot_r, float r2) {
  return v_dot_r < 0.0 ? P.corrections.z * -v_dot_r / (r2 + 0.01 * h2()) : 0.0;
}

void main() {
  uint i = gl_GlobalInvocationID.x;
  if (i >= P.counts.z) return;
  vec4 p4 = b_pos[i];
  vec3 xi = p4.xyz;
  float vol = p4.w;
  vec4 v4 = b_vel[i];
  vec3 vi = v4.xyz;
  float mui = v4.w;
  float pb = b_pressure[i];
  float own = b_rest[i].w;
  vec3 f = vec3(0.0);
  {
    NEIGHBOUR_RUNS(cell_start, xi) {
      for (uint j = run_begin; j < run_end; ++j) {
        vec4 pj = texelFetch(s_pos, int(j));
        float dx = xi.x - pj.x, dy = xi.y - pj.y, dz = xi.z - pj.z;
        float r2 = dx * dx + dy * dy + dz * dz;
        if (r2 >= h2() || r2 <= 0.0) continue;
        vec4 vj = texelFetch(s_vel, int(j));
        vec4 dj = texelFetch(s_density, int(j));
        float r = sqrt(r2);
        float hr = h() - r;
        float p = dj.y;
        float pterm = -dj.z * (2.0 * p * dj.w) * P.kernel.w * hr * hr / r;
        float vterm = dj.z * 0.5 * (pj.w + mui) * P.material.x * hr;
        f.x += pterm * dx + vterm * (vj.x - vi.x);
        f.y += pterm * dy + vterm * (vj.y - vi.y);
        f.z += pterm * dz + vterm * (vj.z - vi.z);
      }
    }
  }
  b_force[i] = vec4(f * vol, 0.0);
  vec3 c = vec3(0.0);
  if (P.counts.y > 0u) {
    NEIGHBOUR_RUNS(w_cell_start, xi) {
      for (uint j = run_begin; j < run_end; ++j) {
        vec4 pj = texelFetch(w_a, int(j));
        float dx = xi.x - pj.x, dy = xi.y - pj.y, dz = xi.z - pj.z;
        float r2 = dx * dx + dy * dy + dz * dz;
        if (r2 >= h2() || r2 <= 0.0) continue;
        float r = sqrt(r2);
        float hr = h() - r;
        vec4 vj = texelFetch(w_b, int(j));
        float dvx = vj.x - vi.x, dvy = vj.y - vi.y, dvz = vj.z - vi.z;
        float damping = contact_viscous_pressure(-(dvx * dx + dvy * dy + dvz * dz), r2);
        float pterm = -pj.w * (pb + pb + damping) * P.kernel.w * hr * hr / r;
        float vterm = pj.w * 0.5 * (vj.w + mui) * P.material.x * hr;
        c.x += pterm * dx + vterm * dvx;
        c.y += pterm * dy + vterm * dvy;
        c.z += pterm * dz + vterm * dvz;
      }
    }
  }
  // Other bodies' particles; none to visit with a single dynamic body (all would be skipped).
  if (P.counts.w > 1u) {
    NEIGHBOUR_RUNS(v_cell_start, xi) {
      for (uint j = run_begin; j < run_end; ++j) {
        vec4 cj = texelFetch(v_c, int(j));
        if (cj.y == own) continue;
        vec4 pj = texelFetch(v_a, int(j));
        float dx = xi.x - pj.x, dy = xi.y - pj.y, dz = xi.z - pj.z;
        float r2 = dx * dx + dy * dy + dz * dz;
        if (r2 >= h2() || r2 <= 0.0) continue;
        float r = sqrt(r2);
        float hr = h() - r;
        vec4 vj = texelFetch(v_b, int(j));
        float dvx = vj.x - vi.x, dvy = vj.y - vi.y, dvz = vj.z - vi.z;
        float damping = contact_viscous_pressure(-(dvx * dx + dvy * dy + dvz * dz), r2);
        float pterm = -pj.w * (pb + b_pressure[uint(cj.z)] + damping) * P.kernel.w * hr * hr / r;
        float vterm = pj.w * 0.5 * (vj.w + mui) * P.material.x * hr;
        c.x += pterm * dx + vterm * dvx;
        c.y += pterm * dy + vterm * dvy;
        c.z += pterm * dz + vterm * dvz;
      }
    }
  }
  b_contact[i] = vec4(c * vol, 0.0);
}
