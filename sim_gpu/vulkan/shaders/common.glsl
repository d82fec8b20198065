// Shared declarations of every compute pass: the parameter block, the binding table and the
// uniform-grid helpers. The grid and run layout mirror hapfluid/sim/neighbour_grid.hpp exactly
// (same cell index, same 9 runs of 3 cells along x), so both backends visit neighbours in the
// same order and sum in the same order.
#include "bindings.glsl"

layout(std140, set = 0, binding = BINDING_PARAMS) uniform Params {
  vec4 kernel;        // h, h^2, poly6 constant, spiky gradient constant
  vec4 material;      // viscosity Laplacian constant, fluid particle mass, rho0, stiffness k
  vec4 gravity_dt;    // gravity (m/s^2), dt (s)
  vec4 clamp_lo;      // last-resort clamp of fluid positions: the first wall layer on walled
  vec4 clamp_hi;      // sides, the box face on open sides (SimulationParams::clamp_lo/hi)
  vec4 grid_origin;   // min corner (m), cell size (m)
  ivec4 grid_dims;    // cells along x, y, z; cell count
  uvec4 counts;       // fluid, static solid, dynamic body particles; dynamic bodies
  vec4 corrections;   // clamp of the pressure force's first-moment correction c: min, max
                      // (gradient_correction.hpp); contact damping alpha rho0 c h, Pa s
                      // (contact_damping.hpp); unused
  vec4 dfsph_kernel;  // incompressible solver: cubic spline h^2, 1 / h, W scale, gradient scale
  vec4 dfsph_a;       // fluid particle volume m / rho0; density and divergence tolerances; XSPH
  vec4 dfsph_b;       // fewest neighbours of a divergence estimate; fluid viscosity (Pa s);
                      // 0.01 h^2; settling: the velocity kept after a step (1 when running)
  ivec4 dfsph_c;      // fewest density and divergence iterations, most iterations, workgroups
                      // of 64 over the fluid
  ivec4 dfsph_d;      // fluid neighbours a particle's list holds; unused
} P;

float h() { return P.kernel.x; }
float h2() { return P.kernel.y; }

int cell_coord(int axis, float p) {
  int c = int((p - P.grid_origin[axis]) / P.grid_origin.w);
  return c < 0 ? 0 : (c >= P.grid_dims[axis] ? P.grid_dims[axis] - 1 : c);
}
uint cell_of(vec3 p) {
  return uint(cell_coord(0, p.x) + P.grid_dims.x * (cell_coord(1, p.y) + P.grid_dims.y * cell_coord(2, p.z)));
}

// Neighbour loops: NEIGHBOUR_RUNS(cell_starts, p) { for (uint j = run_begin; j < run_end; ++j) ... }
// visits the 9 runs of (up to) 3 consecutive cells along x around p, skipping empty runs, in
// the order of for_each_neighbour_run.
#define NEIGHBOUR_RUNS(CELL_STARTS, POS)                                                        \
  ivec3 nc_ = ivec3(cell_coord(0, POS.x), cell_coord(1, POS.y), cell_coord(2, POS.z));           \
  int nx0_ = nc_.x > 0 ? nc_.x - 1 : 0, nx1_ = nc_.x + 1 < P.grid_dims.x ? nc_.x + 1 : nc_.x;   \
  for (int dz_ = -1; dz_ <= 1; ++dz_)                                                           \
    for (int dy_ = -1; dy_ <= 1; ++dy_)                                                         \
      for (int once_ = 0, iz_ = nc_.z + dz_, iy_ = nc_.y + dy_,                                 \
               row_ = P.grid_dims.x * (iy_ + P.grid_dims.y * iz_),                              \
               ok_ = int(iz_ >= 0 && iz_ < P.grid_dims.z && iy_ >= 0 && iy_ < P.grid_dims.y);   \
           once_ < ok_; ++once_)                                                                \
        for (uint run_begin = texelFetch(CELL_STARTS, row_ + nx0_).x,                          \
                  run_end = texelFetch(CELL_STARTS, row_ + nx1_ + 1).x,                        \
                  once2_ = 0; once2_ < 1 && run_begin < run_end; ++once2_)
