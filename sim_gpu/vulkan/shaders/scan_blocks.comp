#version 450
#extension GL_GOOGLE_include_directive : require
// Prefix sum, pass 2 of 3: one workgroup scans the block totals in place (exclusive) and
// writes the grand total as the last cell start.
#include "common.glsl"
layout(local_size_x = 256) in;
layout(push_constant) uniform Push { uint count; uint count_base; uint start_base; uint pad; } pc;
layout(std430, binding = BINDING_CELL_START) writeonly buffer CellStart { uint cell_start[]; };
layout(std430, binding = BINDING_BLOCK_SUMS) buffer BlockSums { uint block_sums[]; };
shared uint partial[256];

void main() {
  uint t = gl_LocalInvocationID.x;
  uint blocks = (pc.count + 1023u) / 1024u;
  uint per_thread = (blocks + 255u) / 256u;
  uint first = t * per_thread;
  uint total = 0u;
  for (uint k = 0u; k < per_thread; ++k)
    if (first + k < blocks) total += block_sums[first + k];
  partial[t] = total;
  barrier();
  for (uint offset = 1u; offset < 256u; offset <<= 1) {
    uint add = t >= offset ? partial[t - offset] : 0u;
    barrier();
    partial[t] += add;
    barrier();
  }
  uint running = partial[t] - total;
  for (uint k = 0u; k < per_thread; ++k) {
    if (first + k < blocks) {
      uint v = block_sums[first + k];
      block_sums[first + k] = running;
      running += v;
    }
  }
  if (t == 255u) cell_start[pc.start_base + pc.count] = partial[255];
}
