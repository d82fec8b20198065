#version 450
#extension GL_GOOGLE_include_directive : require
// Counting sort, scatter: each particle goes to the slot cell_start + rank of its cell.
#include "common.glsl"
layout(local_size_x = 64) in;
layout(push_constant) uniform Push {
  uint particle_count;
  uint particle_base;  // offset into CELL_OF / RANK / ORDER
  uint start_base;     // offset into CELL_START
  uint pad;
} pc;
layout(std430, binding = BINDING_CELL_START) readonly buffer CellStart { uint cell_start[]; };
layout(std430, binding = BINDING_CELL_OF) readonly buffer CellOf { uint cell_of_particle[]; };
layout(std430, binding = BINDING_RANK) readonly buffer Rank { uint rank[]; };
layout(std430, binding = BINDING_ORDER) writeonly buffer Order { uint order[]; };

void main() {
  uint i = gl_GlobalInvocationID.x;
  if (i >= pc.particle_count) return;
  uint c = cell_of_particle[pc.particle_base + i];
  order[pc.particle_base + cell_start[pc.start_base + c] + rank[pc.particle_base + i]] = i;
}
