#version 450
#extension GL_GOOGLE_include_directive : require
// Prefix sum, pass 3 of 3: add each block's offset to its cells, and clear the counts (read by
// pass 1 already) for the next sort, which saves a fill command and its barrier per step.
#include "common.glsl"
layout(local_size_x = 256) in;
layout(push_constant) uniform Push { uint count; uint count_base; uint start_base; uint pad; } pc;
layout(std430, binding = BINDING_CELL_START) buffer CellStart { uint cell_start[]; };
layout(std430, binding = BINDING_BLOCK_SUMS) readonly buffer BlockSums { uint block_sums[]; };
layout(std430, binding = BINDING_CELL_COUNT) writeonly buffer CellCount { uint cell_count[]; };

void main() {
  uint c = gl_GlobalInvocationID.x;
  if (c >= pc.count) return;
  cell_start[pc.start_base + c] += block_sums[c / 1024u];
  cell_count[pc.count_base + c] = 0u;
}
