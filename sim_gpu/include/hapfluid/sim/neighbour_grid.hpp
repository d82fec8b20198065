// Uniform grid of cell size h (the support radius) for neighbour search (§3.3.1): particles are
// sorted by cell with a stable counting sort, so the particles of one cell are contiguous and a
// neighbour query reads 9 contiguous runs (3 cells along x each) of the 27 surrounding cells.
// The Vulkan backend builds the same layout (cell index, count, exclusive prefix sum, scatter
// ranked by particle index), so both backends visit neighbours in the same order.
#pragma once

#include <cstdint>
#include <vector>

namespace hapfluid::sim {

struct GridGeometry {
  float origin[3] = {0, 0, 0};  // min corner, m
  float cell_size = 1;          // = support radius h, m
  int dims[3] = {1, 1, 1};

  std::size_t cell_count() const {
    return static_cast<std::size_t>(dims[0]) * static_cast<std::size_t>(dims[1]) * static_cast<std::size_t>(dims[2]);
  }
  // Cell coordinate along one axis, clamped into the grid (positions are kept inside the domain;
  // the clamp only guards the index).
  int coord(int axis, float p) const {
    int c = static_cast<int>((p - origin[axis]) / cell_size);
    return c < 0 ? 0 : (c >= dims[axis] ? dims[axis] - 1 : c);
  }
  std::uint32_t cell_index(int cx, int cy, int cz) const {
    return static_cast<std::uint32_t>(cx + dims[0] * (cy + dims[1] * cz));
  }
  std::uint32_t cell_of(float x, float y, float z) const { return cell_index(coord(0, x), coord(1, y), coord(2, z)); }
};

// A grid covering [lo, hi] (m) with cells of size h and one spare cell on every side.
GridGeometry make_grid(const float lo[3], const float hi[3], float h);

// The result of sorting a particle set: cell_start[c]..cell_start[c+1] are the sorted positions
// of the particles in cell c; order[k] is the unsorted index of the k-th sorted particle.
struct CellSort {
  std::vector<std::uint32_t> cell_start;  // cell_count + 1 entries
  std::vector<std::uint32_t> order;
  std::vector<std::uint32_t> cell_of;     // scratch: cell of each unsorted particle

  // Stable counting sort: particles of a cell keep their relative order (rank by index).
  void sort(const GridGeometry& grid, const float* x, const float* y, const float* z, std::size_t count);

 private:
  std::vector<std::uint32_t> scratch_cursor_;
};

// Visits the sorted ranges [begin, end) of the (up to) 27 cells around a position: 9 runs of 3
// consecutive cells along x. fn(begin, end) is called once per non-empty run.
template <class Fn>
inline void for_each_neighbour_run(const GridGeometry& g, const std::uint32_t* cell_start, float x, float y, float z,
                                   Fn&& fn) {
  const int cx = g.coord(0, x), cy = g.coord(1, y), cz = g.coord(2, z);
  const int x0 = cx > 0 ? cx - 1 : 0, x1 = cx + 1 < g.dims[0] ? cx + 1 : cx;
  for (int dz = -1; dz <= 1; ++dz) {
    const int iz = cz + dz;
    if (iz < 0 || iz >= g.dims[2]) continue;
    for (int dy = -1; dy <= 1; ++dy) {
      const int iy = cy + dy;
      if (iy < 0 || iy >= g.dims[1]) continue;
      const std::uint32_t row = g.cell_index(0, iy, iz);
      const std::uint32_t begin = cell_start[row + x0], end = cell_start[row + x1 + 1];
      if (begin < end) fn(begin, end);
    }
  }
}

}  // namespace hapfluid::sim
