#version 450
#extension GL_GOOGLE_include_directive : require
// Per-body force and torque (eqs. 10-12), pass 1 of 2 (the two-pass tree reduction of §4.3):
// one workgroup per chunk of at most 256 particles of one body; fluid force, fluid torque,
// contact force and contact torque about the body's centre of mass, summed as a tree in
// shared memory. Deterministic: fixed chunks, fixed tree, no float atomics.
#include "common.glsl"
layout(local_size_x = 256) in;
layout(std430, binding = BINDING_BODY_CHUNKS) readonly buffer Chunks { uvec4 chunks[]; };  // body, first, count
layout(std430, binding = BINDING_BODY_STATE) readonly buffer State { vec4 state[]; };      // 8 per body
layout(std430, binding = BINDING_B_POS) readonly buffer BPos { vec4 b_pos[]; };
layout(std430, binding = BINDING_B_FORCE) readonly buffer BForce { vec4 b_force[]; };
layout(std430, binding = BINDING_B_CONTACT) readonly buffer BContact { vec4 b_contact[]; };
layout(std430, binding = BINDING_BODY_PARTIALS) writeonly buffer Partials { vec4 partials[]; };  // 4 per chunk
shared vec3 sums[4][256];

void main() {
  uint t = gl_LocalInvocationID.x;
  uvec4 chunk = chunks[gl_WorkGroupID.x];
  vec3 ff = vec3(0.0), ft = vec3(0.0), cf = vec3(0.0), ct = vec3(0.0);
  if (t < chunk.z) {
    uint i = chunk.y + t;
    vec3 arm = b_pos[i].xyz - state[8u * chunk.x].xyz;
    ff = b_force[i].xyz;
    cf = b_contact[i].xyz;
    ft = cross(arm, ff);
    ct = cross(arm, cf);
  }
  sums[0][t] = ff; sums[1][t] = ft; sums[2][t] = cf; sums[3][t] = ct;
  barrier();
  for (uint s = 128u; s > 0u; s >>= 1) {
    if (t < s)
      for (int q = 0; q < 4; ++q) sums[q][t] += sums[q][t + s];
    barrier();
  }
  if (t < 4u) partials[4u * gl_WorkGroupID.x + t] = vec4(sums[t][0], 0.0);
}
