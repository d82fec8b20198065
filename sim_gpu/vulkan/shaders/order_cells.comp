#version 450
#extension GL_GOOGLE_include_directive : require
// Counting sort, deterministic order: atomics hand out ranks in arrival order, which changes
// from run to run; sorting each cell's slots by particle index restores the stable order of
// the CPU's counting sort (rank within the cell by particle index). Cells hold a few
// particles, so an insertion sort per cell is cheap.
#include "common.glsl"
layout(local_size_x = 64) in;
layout(push_constant) uniform Push { uint cell_count; uint particle_base; uint start_base; uint pad; } pc;
layout(std430, binding = BINDING_CELL_START) readonly buffer CellStart { uint cell_start[]; };
layout(std430, binding = BINDING_ORDER) buffer Order { uint order[]; };

void main() {
  uint c = gl_GlobalInvocationID.x;
  if (c >= pc.cell_count) return;
  uint begin = pc.particle_base + cell_start[pc.start_base + c];
  uint end = pc.particle_base + cell_start[pc.start_base + c + 1u];
  for (uint k = begin + 1u; k < end; ++k) {
    uint value = order[k];
    uint j = k;
    while (j > begin && order[j - 1u] > value) {
      order[j] = order[j - 1u];
      --j;
    }
    order[j] = value;
  }
}
