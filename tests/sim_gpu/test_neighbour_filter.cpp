// The candidate filter of the neighbour search (sim_gpu/src/neighbour_filter.hpp): the vector
// filter this CPU runs must list exactly the neighbours the portable one lists, in the same order
// with the same offsets, or the solver's results would depend on the machine it runs on.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

#include "neighbour_filter.hpp"

using namespace hapfluid::sim::detail;

namespace {

struct Listed {
  std::vector<std::uint32_t> index;
  std::vector<float> dx, dy, dz;
  std::uint32_t n = 0;
};

Listed run(FilterFn filter, const std::vector<float>& x, const std::vector<float>& y, const std::vector<float>& z,
           std::uint32_t begin, std::uint32_t end, float xi, float yi, float zi, float h2) {
  Listed l;
  const std::size_t room = (end - begin) + kFilterSlack;
  l.index.assign(room, 0), l.dx.assign(room, 0), l.dy.assign(room, 0), l.dz.assign(room, 0);
  l.n = filter(x.data(), y.data(), z.data(), begin, end, xi, yi, zi, h2, {l.index.data(), l.dx.data(), l.dy.data(), l.dz.data()});
  return l;
}

}  // namespace

TEST(NeighbourFilter, TheVectorFilterListsWhatTheScalarOneLists) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> coord(-0.03f, 0.03f);
  const float h = 0.024f;
  // Runs of every length from 0 to 40 (whole vectors and every remainder), at every offset of a
  // vector boundary, some candidates exactly at r = h (not neighbours: the support is open).
  std::vector<float> x(80), y(80), z(80);
  for (int trial = 0; trial < 200; ++trial) {
    for (std::size_t j = 0; j < x.size(); ++j) x[j] = coord(rng), y[j] = coord(rng), z[j] = coord(rng);
    x[5] = h, y[5] = 0, z[5] = 0;
    const std::uint32_t begin = static_cast<std::uint32_t>(trial % 9), end = begin + static_cast<std::uint32_t>(trial % 41);
    const Listed fast = run(neighbour_filter(), x, y, z, begin, end, 0, 0, 0, h * h);
    const Listed reference = run(filter_scalar, x, y, z, begin, end, 0, 0, 0, h * h);
    ASSERT_EQ(fast.n, reference.n) << "run [" << begin << ", " << end << ")";
    for (std::uint32_t k = 0; k < reference.n; ++k) {
      EXPECT_EQ(fast.index[k], reference.index[k]);
      EXPECT_EQ(fast.dx[k], reference.dx[k]);
      EXPECT_EQ(fast.dy[k], reference.dy[k]);
      EXPECT_EQ(fast.dz[k], reference.dz[k]);
    }
  }
}

// A particle whose position went non-finite must not be anyone's neighbour (the finite-state
// check then names it); the filter must neither list it nor read past the run to decide.
TEST(NeighbourFilter, ANonFiniteCandidateIsNoNeighbour) {
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  const std::vector<float> x{0.001f, nan, inf, 0.002f, -inf}, y(5, 0.0f), z(5, 0.0f);
  for (FilterFn filter : {neighbour_filter(), FilterFn{filter_scalar}}) {
    const Listed l = run(filter, x, y, z, 0, 5, 0, 0, 0, 0.01f);
    ASSERT_EQ(l.n, 2u);
    EXPECT_EQ(l.index[0], 0u);
    EXPECT_EQ(l.index[1], 3u);
  }
}
