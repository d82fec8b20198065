// Which screen tiles can hold fluid this frame, found on the CPU from the particles themselves.
// On a software rasteriser every compute invocation costs tens of nanoseconds even when it
// returns at once, so the filter and composite passes run only over tiles that a splat's
// screen-space square touches (conservatively: one texel of margin). Pixels elsewhere keep the
// scene colour (copied) and a "no fluid" depth (cleared).
#pragma once

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

namespace hapfluid::render {

constexpr uint32_t fluid_tile_texels = 8;  // half-resolution texels per tile side (16 pixels)

struct TileGrid {
  uint32_t half_width, half_height;  // fluid buffer size in texels
  uint32_t tiles_x() const { return (half_width + fluid_tile_texels - 1) / fluid_tile_texels; }
  uint32_t tiles_y() const { return (half_height + fluid_tile_texels - 1) / fluid_tile_texels; }
};

// Appends to `tiles` (cleared first) the packed index (x | y << 16) of every tile touched by a
// splat of radius `splat_radius_m` around one of `centres_m`, seen through `view` and the
// symmetric perspective `proj`, and writes to `visible_m` (if given) the centres of the splats
// that reach the screen at all: only those are drawn (frustum culling). `scratch` is reused
// between frames to avoid allocation. Returns the number of visible centres.
size_t find_fluid_tiles(const std::vector<glm::vec3>& centres_m, float splat_radius_m, const glm::mat4& view,
                        const glm::mat4& proj, float near_m, const TileGrid& grid, std::vector<uint8_t>& scratch,
                        std::vector<uint32_t>& tiles, glm::vec3* visible_m = nullptr);

// Every tile of the grid (debug views that colour pixels without fluid too).
void all_tiles(const TileGrid& grid, std::vector<uint32_t>& tiles);

}  // namespace hapfluid::render
