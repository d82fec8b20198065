#version 450
#extension GL_GOOGLE_include_directive : require
// Forces on fluid particles (Algorithm 1, lines 4-12), as acceleration a = f / m = sum / rho:
//   pressure (eq. 5):        -V_p sum_i V_i (P_p + P_i) grad W
//   viscosity (eqs. 6, 9):    V_p sum_i V_i (mu_p + mu_i) / 2 (v_i - v_p) lap W
// Wall and body particles take the fluid particle's own pressure (pressure mirroring).
// Mirrors CpuSolver::compute_fluid_forces term by term. Neighbour
// data come through texel buffers; velocity, density and pressure are fetched only for
// particles inside the support radius.
#include "common.glsl"
layout(local_size_x = 64) in;
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

vec3 a;
vec3 xi, vi;
float pi_, mui;

// Solid neighbours: pressure mirrored; viscosity (eq. 9 with the solid's mu) on the full
// relative velocity for bodies (no_slip = 1) and on its component along the pair direction
// only for walls (no_slip = 0), which damps bouncing without making walls sticky.
void solid_run(samplerBuffer sa, samplerBuffer sb, uint b, uint e, bool have_c, samplerBuffer sc) {
  for (uint j = b; j < e; ++j) {
    vec4 pj = texelFetch(sa, int(j));
    float dx = xi.x - pj.x, dy = xi.y - pj.y, dz = xi.z - pj.z;
    float r2 = dx * dx + dy * dy + dz * dz;
    if (r2 >= h2() || r2 <= 0.0) continue;
    vec4 vj = texelFetch(sb, int(j));
    float ns = have_c ? texelFetch(sc, int(j)).x : 1.0;
    float r = sqrt(r2);
    float hr = h() - r;
    float pterm = -pj.w * (pi_ + pi_) * P.kernel.w * hr * hr / r;
    float vterm = pj.w * 0.5 * (mui + vj.w) * P.material.x * hr;
    float dvx = vj.x - vi.x, dvy = vj.y - vi.y, dvz = vj.z - vi.z;
    float along = (1.0 - ns) * (dvx * dx + dvy * dy + dvz * dz) / r2;
    a.x += pterm * dx + vterm * (ns * dvx + along * dx);
    a.y += pterm * dy + vterm * (ns * dvy + along * dy);
    a.z += pterm * dz + vterm * (ns * dvz + along * dz);
  }
}

void main() {
  uint i = gl_GlobalInvocationID.x;
  if (i >= P.counts.x) return;
  vec4 p4 = texelFetch(s_pos, int(i));
  xi = p4.xyz;
  mui = p4.w;
  vi = texelFetch(s_vel, int(i)).xyz;
  vec4 di = texelFetch(s_density, int(i));
  pi_ = di.y;
  a = vec3(0.0);
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
        float pterm = -dj.z * (pi_ + dj.y) * P.kernel.w * hr * hr / r;
        float vterm = dj.z * 0.5 * (mui + pj.w) * P.material.x * hr;
        a.x += pterm * dx + vterm * (vj.x - vi.x);
        a.y += pterm * dy + vterm * (vj.y - vi.y);
        a.z += pterm * dz + vterm * (vj.z - vi.z);
      }
    }
  }
  if (P.counts.y > 0u) { NEIGHBOUR_RUNS(w_cell_start, xi) solid_run(w_a, w_b, run_begin, run_end, true, w_c); }
  if (P.counts.z > 0u) { NEIGHBOUR_RUNS(v_cell_start, xi) solid_run(v_a, v_b, run_begin, run_end, false, w_c); }
  float inv_rho = 1.0 / di.x;
  acc[i] = vec4(a.x * inv_rho + P.gravity_dt.x, a.y * inv_rho + P.gravity_dt.y, a.z * inv_rho + P.gravity_dt.z, 0.0);
}
