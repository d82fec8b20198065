#version 450
#extension GL_GOOGLE_include_directive : require
// Fluid particles into cell order (the CPU's FluidParticles::permute): S[k] = F[order[k]].
#include "common.glsl"
layout(local_size_x = 64) in;
layout(std430, binding = BINDING_ORDER) readonly buffer Order { uint order[]; };
layout(std430, binding = BINDING_F_POS) readonly buffer FPos { vec4 f_pos[]; };
layout(std430, binding = BINDING_F_VEL) readonly buffer FVel { vec4 f_vel[]; };
layout(std430, binding = BINDING_F_ID) readonly buffer FId { uint f_id[]; };
layout(std430, binding = BINDING_S_POS) writeonly buffer SPos { vec4 s_pos[]; };
layout(std430, binding = BINDING_S_VEL) writeonly buffer SVel { vec4 s_vel[]; };
layout(std430, binding = BINDING_S_ID) writeonly buffer SId { uint s_id[]; };

void main() {
  uint k = gl_GlobalInvocationID.x;
  if (k >= P.counts.x) return;
  uint i = order[k];
  s_pos[k] = f_pos[i];
  s_vel[k] = f_vel[i];
  s_id[k] = f_id[i];
}
