#version 450
#extension GL_GOOGLE_include_directive : require
// Per-body force and torque, pass 2 of 2: one workgroup per body folds its chunks' partial sums
// (a tree again) into BODY_SUMS, the only per-step result the host reads back.
#include "common.glsl"
layout(local_size_x = 64) in;
layout(push_constant) uniform Push { uint chunk_count; uint pad0, pad1, pad2; } pc;
layout(std430, binding = BINDING_BODY_CHUNKS) readonly buffer Chunks { uvec4 chunks[]; };
layout(std430, binding = BINDING_BODY_PARTIALS) readonly buffer Partials { vec4 partials[]; };
layout(std430, binding = BINDING_BODY_SUMS) writeonly buffer Sums { vec4 body_sums[]; };  // 4 per body
shared vec3 sums[4][64];

void main() {
  uint t = gl_LocalInvocationID.x;
  uint body = gl_WorkGroupID.x;
  vec3 acc[4] = vec3[4](vec3(0.0), vec3(0.0), vec3(0.0), vec3(0.0));
  for (uint c = t; c < pc.chunk_count; c += 64u)
    if (chunks[c].x == body)
      for (int q = 0; q < 4; ++q) acc[q] += partials[4u * c + uint(q)].xyz;
  for (int q = 0; q < 4; ++q) sums[q][t] = acc[q];
  barrier();
  for (uint s = 32u; s > 0u; s >>= 1) {
    if (t < s)
      for (int q = 0; q < 4; ++q) sums[q][t] += sums[q][t + s];
    barrier();
  }
  if (t < 4u) body_sums[4u * body + t] = vec4(sums[t][0], 0.0);
}
