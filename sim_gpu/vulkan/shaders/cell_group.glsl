// One invocation per grid cell, holding up to CELL_GROUP of its particles in registers: every
// particle of a cell has the same 27-cell neighbourhood (the same 9 runs), so each neighbour
// candidate is fetched once per cell instead of once per particle, about 8 times fewer texel
// fetches, the cost that dominates on lavapipe. Each particle still sums its terms
// in run order, candidate by candidate, exactly as the per-particle loop and the CPU do.
#extension GL_EXT_control_flow_attributes : require
#define CELL_GROUP 8
layout(local_size_x = 64) in;

// The 9 runs of cell `c` (dz, dy in -1..1; 3 cells along x), as for_each_neighbour_run.
struct CellRuns {
  int row[9];
  bool valid[9];
  int x0, x1;
};

CellRuns cell_runs(uint c) {
  CellRuns r;
  int cx = int(c) % P.grid_dims.x;
  int cy = (int(c) / P.grid_dims.x) % P.grid_dims.y;
  int cz = int(c) / (P.grid_dims.x * P.grid_dims.y);
  r.x0 = cx > 0 ? cx - 1 : 0;
  r.x1 = cx + 1 < P.grid_dims.x ? cx + 1 : cx;
  int k = 0;
  for (int dz = -1; dz <= 1; ++dz)
    for (int dy = -1; dy <= 1; ++dy, ++k) {
      int iz = cz + dz, iy = cy + dy;
      r.valid[k] = iz >= 0 && iz < P.grid_dims.z && iy >= 0 && iy < P.grid_dims.y;
      r.row[k] = P.grid_dims.x * (iy + P.grid_dims.y * iz);
    }
  return r;
}
