#version 450
#extension GL_GOOGLE_include_directive : require
// Exclusive prefix sum of the cell counts, pass 1 of 3 (no cross-workgroup waits: lavapipe
// gives no forward-progress guarantee): each workgroup scans a block of 1024 counts and writes
// the block total.
#include "common.glsl"
layout(local_size_x = 256) in;
layout(push_constant) uniform Push { uint count; uint count_base; uint start_base; uint pad; } pc;
layout(std430, binding = BINDING_CELL_COUNT) readonly buffer CellCount { uint cell_count[]; };
layout(std430, binding = BINDING_CELL_START) writeonly buffer CellStart { uint cell_start[]; };
layout(std430, binding = BINDING_BLOCK_SUMS) writeonly buffer BlockSums { uint block_sums[]; };
shared uint partial[256];

void main() {
  uint t = gl_LocalInvocationID.x;
  uint first = gl_WorkGroupID.x * 1024u + t * 4u;
  uint v[4];
  uint total = 0u;
  for (uint k = 0u; k < 4u; ++k) {
    v[k] = first + k < pc.count ? cell_count[pc.count_base + first + k] : 0u;
    total += v[k];
  }
  partial[t] = total;
  barrier();
  for (uint offset = 1u; offset < 256u; offset <<= 1) {
    uint add = t >= offset ? partial[t - offset] : 0u;
    barrier();
    partial[t] += add;
    barrier();
  }
  uint running = partial[t] - total;
  for (uint k = 0u; k < 4u; ++k) {
    if (first + k < pc.count) cell_start[pc.start_base + first + k] = running;
    running += v[k];
  }
  if (t == 255u) block_sums[gl_WorkGroupID.x] = partial[255];
}
