#include "fluid_tiles.hpp"

#include <algorithm>
#include <cmath>

namespace hapfluid::render {

size_t find_fluid_tiles(const std::vector<glm::vec3>& centres, float radius, const glm::mat4& view, const glm::mat4& proj,
                        float near_m, const TileGrid& grid, std::vector<uint8_t>& marks, std::vector<uint32_t>& tiles,
                        glm::vec3* visible) {
  size_t visible_count = 0;
  const uint32_t nx = grid.tiles_x(), ny = grid.tiles_y();
  marks.assign(size_t(nx) * ny, 0);
  tiles.clear();
  const float w = float(grid.half_width), h = float(grid.half_height);
  // The splat quad is view-aligned at the centre's depth (splat.vert), so its screen bounds are
  // the projections of its corners: ndc = P00 x / d, P11 y / d at depth d.
  const float p00 = proj[0][0], p11 = proj[1][1];
  const int max_tx = int(nx) - 1, max_ty = int(ny) - 1;
  for (const glm::vec3& c : centres) {
    if (!std::isfinite(c.x) || !std::isfinite(c.y) || !std::isfinite(c.z)) continue;  // a broken frame
    const glm::vec3 v = glm::vec3(view * glm::vec4(c, 1.0f));
    const float depth = -v.z;
    if (depth <= near_m) continue;  // the quad lies behind the near plane: clipped on the GPU
    const float xa = p00 * (v.x - radius) / depth, xb = p00 * (v.x + radius) / depth;
    const float ya = p11 * (v.y - radius) / depth, yb = p11 * (v.y + radius) / depth;
    // ndc -> texel, one texel of margin for rasterisation rounding and the filter's reach.
    const float x0 = (std::min(xa, xb) * 0.5f + 0.5f) * w - 1.0f, x1 = (std::max(xa, xb) * 0.5f + 0.5f) * w + 1.0f;
    const float y0 = (std::min(ya, yb) * 0.5f + 0.5f) * h - 1.0f, y1 = (std::max(ya, yb) * 0.5f + 0.5f) * h + 1.0f;
    if (x1 < 0.0f || y1 < 0.0f || x0 >= w || y0 >= h) continue;  // off screen: not drawn either
    if (visible) visible[visible_count] = c;
    ++visible_count;
    const int tx0 = std::clamp(int(std::floor(x0)) / int(fluid_tile_texels), 0, max_tx);
    const int tx1 = std::clamp(int(std::floor(x1)) / int(fluid_tile_texels), 0, max_tx);
    const int ty0 = std::clamp(int(std::floor(y0)) / int(fluid_tile_texels), 0, max_ty);
    const int ty1 = std::clamp(int(std::floor(y1)) / int(fluid_tile_texels), 0, max_ty);
    for (int ty = ty0; ty <= ty1; ++ty)
      for (int tx = tx0; tx <= tx1; ++tx) marks[size_t(ty) * nx + size_t(tx)] = 1;
  }
  for (uint32_t ty = 0; ty < ny; ++ty)
    for (uint32_t tx = 0; tx < nx; ++tx)
      if (marks[size_t(ty) * nx + tx]) tiles.push_back(tx | (ty << 16));
  return visible_count;
}

void all_tiles(const TileGrid& grid, std::vector<uint32_t>& tiles) {
  tiles.clear();
  for (uint32_t ty = 0; ty < grid.tiles_y(); ++ty)
    for (uint32_t tx = 0; tx < grid.tiles_x(); ++tx) tiles.push_back(tx | (ty << 16));
}

}  // namespace hapfluid::render
