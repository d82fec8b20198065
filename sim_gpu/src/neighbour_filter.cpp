#include "neighbour_filter.hpp"

#include <array>

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#include <immintrin.h>
#define HAPFLUID_FILTER_AVX2 1
#endif

namespace hapfluid::sim::detail {

std::uint32_t filter_scalar(const float* x, const float* y, const float* z, std::uint32_t begin, std::uint32_t end,
                            float xi, float yi, float zi, float h2, FilterOutput out) {
  std::uint32_t n = 0;
  for (std::uint32_t j = begin; j < end; ++j) {
    const float dx = xi - x[j], dy = yi - y[j], dz = zi - z[j];
    // Branch-free: always written, kept only for a hit (a NaN position is never a hit).
    out.index[n] = j, out.dx[n] = dx, out.dy[n] = dy, out.dz[n] = dz;
    n += (dx * dx + dy * dy + dz * dz < h2) ? 1u : 0u;
  }
  return n;
}

#ifdef HAPFLUID_FILTER_AVX2
namespace {

// For each 8-bit hit mask, the lanes of the hits in order: the permutation that packs them left.
struct PackTable {
  alignas(32) std::int32_t lanes[256][8];
};

constexpr PackTable make_pack_table() {
  PackTable t{};
  for (int mask = 0; mask < 256; ++mask) {
    int k = 0;
    for (int lane = 0; lane < 8; ++lane)
      if (mask & (1 << lane)) t.lanes[mask][k++] = lane;
    for (; k < 8; ++k) t.lanes[mask][k] = 0;
  }
  return t;
}

constexpr PackTable kPackTable = make_pack_table();

__attribute__((target("avx2,fma,popcnt"))) std::uint32_t filter_avx2(const float* x, const float* y, const float* z,
                                                                      std::uint32_t begin, std::uint32_t end, float xi,
                                                                      float yi, float zi, float h2, FilterOutput out) {
  const __m256 pxi = _mm256_set1_ps(xi), pyi = _mm256_set1_ps(yi), pzi = _mm256_set1_ps(zi), ph2 = _mm256_set1_ps(h2);
  const __m256i lane = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
  std::uint32_t n = 0;
  for (std::uint32_t j = begin; j < end; j += 8) {
    // The last block of a run is loaded under a mask: lanes past its end read nothing and miss.
    const __m256i valid = _mm256_cmpgt_epi32(_mm256_set1_epi32(static_cast<int>(end - j)), lane);
    const __m256 dx = _mm256_sub_ps(pxi, _mm256_maskload_ps(x + j, valid));
    const __m256 dy = _mm256_sub_ps(pyi, _mm256_maskload_ps(y + j, valid));
    const __m256 dz = _mm256_sub_ps(pzi, _mm256_maskload_ps(z + j, valid));
    const __m256 r2 = _mm256_fmadd_ps(dx, dx, _mm256_fmadd_ps(dy, dy, _mm256_mul_ps(dz, dz)));
    const __m256 hit = _mm256_and_ps(_mm256_cmp_ps(r2, ph2, _CMP_LT_OQ), _mm256_castsi256_ps(valid));
    const int mask = _mm256_movemask_ps(hit);
    if (mask == 0) continue;
    const __m256i pack = _mm256_load_si256(reinterpret_cast<const __m256i*>(kPackTable.lanes[mask]));
    const __m256i index = _mm256_add_epi32(_mm256_set1_epi32(static_cast<int>(j)), lane);
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(out.index + n), _mm256_permutevar8x32_epi32(index, pack));
    _mm256_storeu_ps(out.dx + n, _mm256_permutevar8x32_ps(dx, pack));
    _mm256_storeu_ps(out.dy + n, _mm256_permutevar8x32_ps(dy, pack));
    _mm256_storeu_ps(out.dz + n, _mm256_permutevar8x32_ps(dz, pack));
    n += static_cast<std::uint32_t>(__builtin_popcount(static_cast<unsigned>(mask)));
  }
  return n;
}

}  // namespace
#endif

FilterFn neighbour_filter() {
#ifdef HAPFLUID_FILTER_AVX2
  static const FilterFn chosen = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma") ? filter_avx2 : filter_scalar;
  return chosen;
#else
  return filter_scalar;
#endif
}

}  // namespace hapfluid::sim::detail
