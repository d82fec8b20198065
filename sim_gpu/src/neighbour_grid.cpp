#include "hapfluid/sim/neighbour_grid.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

namespace hapfluid::sim {

GridGeometry make_grid(const float lo[3], const float hi[3], float h) {
  GridGeometry g;
  g.cell_size = h;
  std::size_t cells = 1;
  for (int a = 0; a < 3; ++a) {
    g.origin[a] = lo[a] - h;
    g.dims[a] = static_cast<int>(std::ceil((hi[a] - lo[a]) / h)) + 2;
    cells *= static_cast<std::size_t>(g.dims[a]);
  }
  // 64 M cells is 256 MB per cell table: a domain that large for its h is a scene error.
  if (cells > (std::size_t{1} << 26))
    throw std::runtime_error("neighbour grid would have " + std::to_string(cells) +
                             " cells: the domain is too large for the support radius h = " + std::to_string(h) + " m");
  return g;
}

void CellSort::sort(const GridGeometry& grid, const float* x, const float* y, const float* z, std::size_t count) {
  const std::size_t cells = grid.cell_count();
  cell_start.assign(cells + 1, 0);
  cell_of.resize(count);
  order.resize(count);
  for (std::size_t i = 0; i < count; ++i) {
    const std::uint32_t c = grid.cell_of(x[i], y[i], z[i]);
    cell_of[i] = c;
    ++cell_start[c + 1];
  }
  for (std::size_t c = 0; c < cells; ++c) cell_start[c + 1] += cell_start[c];
  // Scatter in index order through a running cursor per cell: stable, hence deterministic.
  std::vector<std::uint32_t>& cursor = scratch_cursor_;
  cursor.assign(cell_start.begin(), cell_start.end() - 1);
  for (std::size_t i = 0; i < count; ++i) order[cursor[cell_of[i]]++] = static_cast<std::uint32_t>(i);
}

}  // namespace hapfluid::sim
