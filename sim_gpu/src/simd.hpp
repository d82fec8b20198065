// The vector tools of the incompressible solver's pair passes. Internal to sim_gpu.
//  - HAPFLUID_CLONES: a pass compiled twice, for AVX2 and for baseline x86-64, picked at load time
//    (not under ThreadSanitizer or clang, whose target_clones differ).
//  - Arithmetic on Packed4 (dfsph_solver.hpp) as one SSE register, through the GCC/Clang vector
//    extension: a pass loads a neighbour's velocity or a pair's gradient whole, with no gathers
//    and no shuffles.
#pragma once

#include <cstring>

#include "hapfluid/sim/dfsph_solver.hpp"

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && !defined(__SANITIZE_THREAD__)
#define HAPFLUID_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define HAPFLUID_CLONES
#endif

namespace hapfluid::sim::detail {

typedef float V4 __attribute__((vector_size(16)));

inline V4 load(const Packed4& p) {
  V4 v;
  std::memcpy(&v, &p, sizeof v);
  return v;
}

inline void store(Packed4& p, V4 v) { std::memcpy(static_cast<void*>(&p), &v, sizeof v); }

inline V4 splat(float s) { return V4{s, s, s, s}; }

// x y z of a vector whose w is ignored.
inline float dot3(V4 a, V4 b) {
  const V4 c = a * b;
  return c[0] + c[1] + c[2];
}

}  // namespace hapfluid::sim::detail
