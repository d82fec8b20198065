// Counting sort, pass 1: the cell of each particle and its arrival rank in that cell (the rank
// is made deterministic later by order_cells). Fluid particles from F_POS, or with BODIES the
// dynamic body particles from B_POS; both share CELL_OF / RANK with an offset.
layout(local_size_x = 64) in;
layout(push_constant) uniform Push {
  uint particle_count;
  uint particle_base;  // offset into CELL_OF / RANK
  uint cell_base;      // offset into CELL_COUNT
  uint pad;
} pc;
#ifdef BODIES
layout(std430, binding = BINDING_B_POS) readonly buffer Pos { vec4 pos[]; };
#else
layout(std430, binding = BINDING_F_POS) readonly buffer Pos { vec4 pos[]; };
#endif
layout(std430, binding = BINDING_CELL_COUNT) buffer CellCount { uint cell_count[]; };
layout(std430, binding = BINDING_CELL_OF) writeonly buffer CellOf { uint cell_of_particle[]; };
layout(std430, binding = BINDING_RANK) writeonly buffer Rank { uint rank[]; };

void main() {
  uint i = gl_GlobalInvocationID.x;
  if (i >= pc.particle_count) return;
  uint c = cell_of(pos[i].xyz);
  cell_of_particle[pc.particle_base + i] = c;
  rank[pc.particle_base + i] = atomicAdd(cell_count[pc.cell_base + c], 1u);
}
