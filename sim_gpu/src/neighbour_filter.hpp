// The candidate filter of the neighbour search: of a run of cell-sorted particles [begin, end),
// the ones within h of a position, left-packed with their offsets. About 15 % of the 27 cells'
// candidates lie within h, so this test runs on every candidate of every particle each step. With
// AVX2 it tests eight contiguous candidates at once and packs the hits through a permutation
// table; without it, one at a time. Internal to sim_gpu.
#pragma once

#include <cstdint>

namespace hapfluid::sim::detail {

// Where the hits of a run go: index[k] the candidate's sorted index, dx/dy/dz[k] = x_i - x_j, for
// k from 0; each array must have room for (end - begin) + kFilterSlack entries, as the vector
// path writes whole registers past the last hit.
struct FilterOutput {
  std::uint32_t* index;
  float *dx, *dy, *dz;
};
inline constexpr std::uint32_t kFilterSlack = 8;

using FilterFn = std::uint32_t (*)(const float* x, const float* y, const float* z, std::uint32_t begin,
                                   std::uint32_t end, float xi, float yi, float zi, float h2, FilterOutput out);

// The fastest filter this CPU runs (chosen once); returns the number of hits.
FilterFn neighbour_filter();

// The portable filter, the reference the vector one is tested against.
std::uint32_t filter_scalar(const float* x, const float* y, const float* z, std::uint32_t begin, std::uint32_t end,
                            float xi, float yi, float zi, float h2, FilterOutput out);

}  // namespace hapfluid::sim::detail
