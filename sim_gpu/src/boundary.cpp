#include "hapfluid/sim/boundary.hpp"

#include <algorithm>
#include <cmath>

#include "hapfluid/sim/neighbour_grid.hpp"

namespace hapfluid::sim {

std::vector<Vec3> wall_particle_positions(const config::Domain& domain, double spacing_m, int layers) {
  const double lo[3] = {domain.box.min_m.x, domain.box.min_m.y, domain.box.min_m.z};
  const double hi[3] = {domain.box.max_m.x, domain.box.max_m.y, domain.box.max_m.z};
  const bool low_wall[3] = {domain.walls.x_min, domain.walls.y_min, domain.walls.floor};
  const bool high_wall[3] = {domain.walls.x_max, domain.walls.y_max, domain.walls.ceiling};
  // Per axis a lattice that fits the box exactly: n cells of spacing close to spacing_m, with
  // the first wall layer half a spacing behind each face, where a fluid lattice would continue.
  int n[3];
  double step[3];
  for (int a = 0; a < 3; ++a) {
    n[a] = std::max(1, static_cast<int>(std::lround((hi[a] - lo[a]) / spacing_m)));
    step[a] = (hi[a] - lo[a]) / n[a];
  }
  std::vector<Vec3> out;
  for (int k = -layers; k < n[2] + layers; ++k)
    for (int j = -layers; j < n[1] + layers; ++j)
      for (int i = -layers; i < n[0] + layers; ++i) {
        const int idx[3] = {i, j, k};
        bool wall = false;
        for (int a = 0; a < 3; ++a) wall = wall || (idx[a] < 0 && low_wall[a]) || (idx[a] >= n[a] && high_wall[a]);
        if (!wall) continue;
        out.push_back({lo[0] + (i + 0.5) * step[0], lo[1] + (j + 0.5) * step[1], lo[2] + (k + 0.5) * step[2]});
      }
  return out;
}

namespace {

template <class Kernel>
std::vector<float> volumes_with(const std::vector<Vec3>& p, float h, Kernel&& w) {
  std::vector<float> volume(p.size(), 0.0f);
  if (p.empty()) return volume;
  float lo[3] = {1e30f, 1e30f, 1e30f}, hi[3] = {-1e30f, -1e30f, -1e30f};
  std::vector<float> x(p.size()), y(p.size()), z(p.size());
  for (std::size_t i = 0; i < p.size(); ++i) {
    x[i] = static_cast<float>(p[i].x), y[i] = static_cast<float>(p[i].y), z[i] = static_cast<float>(p[i].z);
    lo[0] = std::min(lo[0], x[i]), lo[1] = std::min(lo[1], y[i]), lo[2] = std::min(lo[2], z[i]);
    hi[0] = std::max(hi[0], x[i]), hi[1] = std::max(hi[1], y[i]), hi[2] = std::max(hi[2], z[i]);
  }
  const GridGeometry grid = make_grid(lo, hi, h);
  CellSort sort;
  sort.sort(grid, x.data(), y.data(), z.data(), p.size());
  for (std::size_t i = 0; i < p.size(); ++i) {
    double sum = 0;
    for_each_neighbour_run(grid, sort.cell_start.data(), x[i], y[i], z[i], [&](std::uint32_t b, std::uint32_t e) {
      for (std::uint32_t s = b; s < e; ++s) {
        const std::uint32_t k = sort.order[s];
        const float dx = x[i] - x[k], dy = y[i] - y[k], dz = z[i] - z[k];
        sum += w(dx * dx + dy * dy + dz * dz);
      }
    });
    volume[i] = static_cast<float>(1.0 / sum);
  }
  return volume;
}

}  // namespace

std::vector<float> boundary_volumes(const std::vector<Vec3>& p, const KernelConstants& kernel) {
  return volumes_with(p, kernel.h, [&](float r2) { return poly6(kernel, r2); });
}

std::vector<float> boundary_volumes(const std::vector<Vec3>& p, const CubicKernel& kernel) {
  return volumes_with(p, kernel.h, [&](float r2) { return cubic_w(kernel, std::sqrt(r2)); });
}

}  // namespace hapfluid::sim
