#version 450
#extension GL_GOOGLE_include_directive : require
// Makes this step's cell order the persistent order without moving anyone (F[k] = S[k]): used
// once at start, after the initial sort and density pass, so that the first exported frame
// carries densities and pressures aligned with its particles (as the CPU backend does).
#include "common.glsl"
layout(local_size_x = 64) in;
layout(std430, binding = BINDING_S_POS) readonly buffer SPos { vec4 s_pos[]; };
layout(std430, binding = BINDING_S_VEL) readonly buffer SVel { vec4 s_vel[]; };
layout(std430, binding = BINDING_S_ID) readonly buffer SId { uint s_id[]; };
layout(std430, binding = BINDING_F_POS) writeonly buffer FPos { vec4 f_pos[]; };
layout(std430, binding = BINDING_F_VEL) writeonly buffer FVel { vec4 f_vel[]; };
layout(std430, binding = BINDING_F_ID) writeonly buffer FId { uint f_id[]; };

void main() {
  uint k = gl_GlobalInvocationID.x;
  if (k >= P.counts.x) return;
  f_pos[k] = s_pos[k];
  f_vel[k] = s_vel[k];
  f_id[k] = s_id[k];
}
