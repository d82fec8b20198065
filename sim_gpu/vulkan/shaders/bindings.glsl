// Binding numbers of the one descriptor set every pass uses (set 0). Plain #defines so that the
// C++ host code includes this very file: one table, no drift between shaders and host.
//
// Naming: F_ fluid in the persistent order (the order of the last sort), S_ fluid sorted this
// step, W_ static solids (walls, static bodies; sorted once), B_ dynamic body particles
// (grouped per body), V_ the body-particle view sorted by cell this step, D_ the incompressible
// solver's fields (per sorted particle unless marked F). T_ are texel views
// (samplerBuffer) of the arrays neighbour loops read; the rest are storage buffers.
#ifndef HAPFLUID_VULKAN_BINDINGS
#define HAPFLUID_VULKAN_BINDINGS

#define BINDING_PARAMS 0        // uniform Params
#define BINDING_F_POS 1         // vec4 (x, y, z, viscosity)
#define BINDING_F_VEL 2         // vec4 (vx, vy, vz, 0): leap-frog velocity
#define BINDING_F_ID 3          // uint creation index
#define BINDING_S_POS 4         // vec4 (x, y, z, viscosity), cell-sorted
#define BINDING_S_VEL 5         // vec4 (vx, vy, vz, 0)
#define BINDING_S_ID 6          // uint
#define BINDING_S_DENSITY 7     // vec4 (density, pressure, volume, volume correction 1 / c)
#define BINDING_S_ACC 8         // vec4 (ax, ay, az, 0): acceleration of this step
#define BINDING_CELL_COUNT 9    // uint per cell: fluid cells, then body cells
#define BINDING_CELL_START 10   // uint: fluid cells + 1, then body cells + 1
#define BINDING_BLOCK_SUMS 11   // uint per scan block
#define BINDING_CELL_OF 12      // uint per particle: fluid, then body particles
#define BINDING_RANK 13         // uint per particle: arrival order within its cell
#define BINDING_ORDER 14        // uint per sorted slot: fluid, then body particles
#define BINDING_REDUCE 15       // uint partial maxima (float bits) and the final maxima
#define BINDING_T_S_POS 16      // texel views of S_POS, S_VEL, S_DENSITY, fluid cell starts
#define BINDING_T_S_VEL 17
#define BINDING_T_S_DENSITY 18
#define BINDING_T_CELL_START 19
#define BINDING_T_W_A 20        // static solids: vec4 (x, y, z, volume)
#define BINDING_T_W_B 21        // vec4 (vx, vy, vz, viscosity)
#define BINDING_T_W_C 22        // vec4 (no_slip, pressure, body, 0)
#define BINDING_T_W_CELL_START 23
#define BINDING_B_POS 24        // vec4 (x, y, z, volume), grouped per body
#define BINDING_B_VEL 25        // vec4 (vx, vy, vz, viscosity)
#define BINDING_B_REST 26       // vec4 (rx, ry, rz, body): rest offset in body axes
#define BINDING_B_FORCE 27      // vec4 fluid force on the particle (f^haptic), N
#define BINDING_B_CONTACT 28    // vec4 contact force from other solids, N
#define BINDING_B_PRESSURE 29   // float contact pressure, Pa
#define BINDING_V_A 30          // body view sorted by cell: vec4 (x, y, z, volume)
#define BINDING_V_B 31          // vec4 (vx, vy, vz, viscosity)
#define BINDING_V_C 32          // vec4 (pressure, body, source index, 0)
#define BINDING_T_V_A 33
#define BINDING_T_V_B 34
#define BINDING_T_V_C 35
#define BINDING_T_V_CELL_START 36
#define BINDING_BODY_STATE 37   // per body: mat4-like block (position, rotation rows, v, w)
#define BINDING_BODY_CHUNKS 38  // per reduction chunk: uvec4 (body, first, count, 0)
#define BINDING_BODY_PARTIALS 39  // per chunk: 4 vec4 (fluid f, fluid t, contact f, contact t)
#define BINDING_BODY_SUMS 40    // per body: 4 vec4
#define BINDING_D_PARTICLE 41  // vec4, 12 per sorted particle then 2 per particle in F order
                                // (dfsph_common.glsl: D_FIELD ... D_DV_F)
#define BINDING_D_SOLVE 42    // uint: indirect dispatch arguments, solve state, counters,
                              // per-workgroup partial sums (dfsph_common.glsl)
#define BINDING_T_D_WALLS 43  // float texels: the domain walls' volume map (wall_map.hpp)
#define BINDING_T_D_PARTICLE 44  // texel view of D_PARTICLE for neighbour reads
#define BINDING_D_LIST 45    // vec4 per listed pair: V_j grad W_ij (1/m), j; list capacity per sorted particle
#define BINDING_T_D_LIST 46
#define BINDING_D_KAPPA 47   // float per sorted particle: this iteration's stiffness increment
#define BINDING_T_D_KAPPA 48 // its texel view, for the neighbours' reads
#define BINDING_COUNT 49

#endif
