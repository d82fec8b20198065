// Per-particle neighbour lists of the CPU backend: the density pass keeps the candidates within
// h of each fluid particle (fluid, then static solids, then dynamic body particles) and their
// distances, so the force pass visits only true neighbours. One buffer per slot of the thread pool.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace hapfluid::sim::detail {

struct NeighbourRange {
  std::uint32_t offset = 0;   // into the slot's buffer
  std::uint16_t fluid = 0;    // fluid neighbours, then
  std::uint16_t statics = 0;  // static solid neighbours, then
  std::uint16_t bodies = 0;   // dynamic body neighbours
};

struct NeighbourLists {
  std::vector<std::uint32_t> indices;
  // |x_i - x_j| of each listed pair, written by the density pass (its first-moment sum needs it)
  // and read by the force pass over the same positions: one square root per pair and step.
  std::vector<float> distances;
  std::size_t used = 0;
};

}  // namespace hapfluid::sim::detail
