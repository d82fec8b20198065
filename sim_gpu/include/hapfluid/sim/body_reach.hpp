// Which bodies are near another body, for the contact passes between solids.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "hapfluid/sim/particles.hpp"

namespace hapfluid::sim::detail {

// Which bodies have another body within reach: their particles' bounding boxes, grown by the
// support radius, overlap. For a body alone in the fluid the contact passes skip the search
// through the body view, whose candidates would all be the body's own particles (a bucket's
// 3,000 particles each met ~40 of their own for nothing).
class BodyReach {
 public:
  void resize(std::size_t bodies);                     // at set-up: no allocation per step
  void update(const BodyParticles& bp, float reach);  // each step, before the contact passes
  bool near_other(std::int32_t body) const { return near_[static_cast<std::size_t>(body)] != 0; }

 private:
  std::vector<float> lo_, hi_;  // x, y, z per body
  std::vector<char> near_;
};

}  // namespace hapfluid::sim::detail
