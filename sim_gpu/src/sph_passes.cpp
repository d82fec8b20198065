#include "sph_passes.hpp"

#include <algorithm>
#include <cmath>

#include "hapfluid/sim/gradient_correction.hpp"
#include "simd.hpp"

namespace hapfluid::sim::detail {
namespace {

// Appends the candidates of one run that lie within h (branch-free compaction) and returns
// how many were appended. The buffer has room for the whole run.
inline std::uint32_t collect_run(const float* x, const float* y, const float* z, std::uint32_t b, std::uint32_t e,
                                 float xi, float yi, float zi, float h2, std::uint32_t* out) {
  std::uint32_t n = 0;
  for (std::uint32_t j = b; j < e; ++j) {
    const float dx = xi - x[j], dy = yi - y[j], dz = zi - z[j];
    out[n] = j;
    n += (dx * dx + dy * dy + dz * dz < h2) ? 1u : 0u;
  }
  return n;
}

// Over listed neighbours, in one sweep: sum of w_j (h^2 - r^2)^3 (the poly6 shape, eq. 2) and
// sum of w_j (h - r)^2 r (the first-moment kernel's shape, gradient_correction.hpp; zero for
// the particle itself, r = 0); the distances r go to the list for the force pass.
// Weighted (solids, w = V_b) and unweighted (fluid) versions: a run-time choice of the weight
// inside the loop keeps it from vectorising.
struct ShapeSums {
  float poly6 = 0, moment = 0;
};
template <bool kWeighted>
inline ShapeSums shape_sums(const float* x, const float* y, const float* z, const float* w, const std::uint32_t* list,
                            float* distances, std::uint32_t n, float xi, float yi, float zi, const KernelConstants& k) {
  float poly6 = 0, moment = 0;
#pragma omp simd reduction(+ : poly6, moment)
  for (std::uint32_t q = 0; q < n; ++q) {
    const std::uint32_t j = list[q];
    const float dx = xi - x[j], dy = yi - y[j], dz = zi - z[j];
    const float r2 = dx * dx + dy * dy + dz * dz;
    const float r = std::sqrt(r2);
    distances[q] = r;
    const float hr = k.h - r > 0 ? k.h - r : 0.0f;
    if constexpr (kWeighted) {
      poly6 += w[j] * poly6_shape(k, r2);
      moment += w[j] * moment_shape(r, hr);
    } else {
      poly6 += poly6_shape(k, r2);
      moment += moment_shape(r, hr);
    }
  }
  return {poly6, moment};
}

struct Accel {
  float x = 0, y = 0, z = 0;
};

// Fluid-fluid pair terms (see CpuSolver::compute_fluid_forces for the formulas); the pressure
// term carries the first-moment correction 1 / (c_i c_j) (gradient_correction.hpp).
inline void fluid_terms(const FluidParticles& f, const std::uint32_t* list, const float* distances, std::uint32_t n,
                        float xi, float yi, float zi, float vxi, float vyi, float vzi, float pi, float vci, float mui,
                        const KernelConstants& k, Accel& a) {
  float sx = 0, sy = 0, sz = 0;
  const float *x = f.x.data(), *y = f.y.data(), *z = f.z.data(), *vx = f.vx.data(), *vy = f.vy.data(), *vz = f.vz.data();
  const float *vol = f.volume.data(), *pr = f.pressure.data(), *mu = f.viscosity.data(), *vc = f.volume_correction.data();
#pragma omp simd reduction(+ : sx, sy, sz)
  for (std::uint32_t q = 0; q < n; ++q) {
    const std::uint32_t j = list[q];
    const float dx = xi - x[j], dy = yi - y[j], dz = zi - z[j];
    const bool in = distances[q] > 0;  // a particle is in its own list (r = 0): no force on itself
    const float r = in ? distances[q] : k.h;
    const float hr = in ? k.h - r : 0.0f;
    const float pterm = -vol[j] * (pi + pr[j]) * (vci * vc[j]) * spiky_grad_factor(k, r, hr);
    const float vterm = vol[j] * 0.5f * (mui + mu[j]) * viscosity_laplacian_of(k, hr);
    sx += pterm * dx + vterm * (vx[j] - vxi);
    sy += pterm * dy + vterm * (vy[j] - vyi);
    sz += pterm * dz + vterm * (vz[j] - vzi);
  }
  a.x += sx, a.y += sy, a.z += sz;
}

// Fluid-solid pair terms: the solid takes the fluid particle's pressure (mirroring) and keeps its
// own volume, so the pressure pair term is 2 P_i / c_i (passed as pi2c); walls (no_slip = 0)
// would damp only the relative velocity along the pair direction.
inline void solid_terms(const SortedSolids& s, const std::uint32_t* list, const float* distances, std::uint32_t n,
                        float xi, float yi, float zi, float vxi, float vyi, float vzi, float pi2c, float mui,
                        const KernelConstants& k, Accel& a) {
  float sx = 0, sy = 0, sz = 0;
  const float *x = s.x.data(), *y = s.y.data(), *z = s.z.data(), *vx = s.vx.data(), *vy = s.vy.data(), *vz = s.vz.data();
  const float *vol = s.volume.data(), *mu = s.viscosity.data(), *ns = s.no_slip.data();
#pragma omp simd reduction(+ : sx, sy, sz)
  for (std::uint32_t q = 0; q < n; ++q) {
    const std::uint32_t j = list[q];
    const float dx = xi - x[j], dy = yi - y[j], dz = zi - z[j];
    const float r2 = dx * dx + dy * dy + dz * dz;
    const bool in = distances[q] > 0;
    const float r = in ? distances[q] : k.h;
    const float hr = in ? k.h - r : 0.0f;
    const float pterm = -vol[j] * pi2c * spiky_grad_factor(k, r, hr);
    const float vterm = vol[j] * 0.5f * (mui + mu[j]) * viscosity_laplacian_of(k, hr);
    const float dvx = vx[j] - vxi, dvy = vy[j] - vyi, dvz = vz[j] - vzi;
    const float along = (1.0f - ns[j]) * (dvx * dx + dvy * dy + dvz * dz) / (in ? r2 : k.h2);
    sx += pterm * dx + vterm * (ns[j] * dvx + along * dx);
    sy += pterm * dy + vterm * (ns[j] * dvy + along * dy);
    sz += pterm * dz + vterm * (ns[j] * dvz + along * dz);
  }
  a.x += sx, a.y += sy, a.z += sz;
}

// Collects the neighbours of (xi, yi, zi) in one particle set into the list buffer.
std::uint32_t collect(const GridGeometry& g, const std::uint32_t* cell_start, const float* x, const float* y,
                      const float* z, float xi, float yi, float zi, float h2, NeighbourLists& lists) {
  std::uint32_t count = 0;
  for_each_neighbour_run(g, cell_start, xi, yi, zi, [&](std::uint32_t b, std::uint32_t e) {
    if (lists.used + (e - b) > lists.indices.size()) {
      lists.indices.resize(2 * (lists.used + (e - b)) + 1024);
      lists.distances.resize(lists.indices.size());
    }
    const std::uint32_t n = collect_run(x, y, z, b, e, xi, yi, zi, h2, lists.indices.data() + lists.used);
    lists.used += n;
    count += n;
  });
  return count;
}

}  // namespace

HAPFLUID_CLONES
void density_pass(const SimulationParams& p, FluidParticles& f, const std::uint32_t* fluid_cell_start,
                  const SortedSolids& st, const SortedSolids& bv, std::size_t begin, std::size_t end,
                  NeighbourLists& lists, NeighbourRange* ranges) {
  const float h2 = p.kernel.h2, mass = p.fluid_particle_mass_kg, rho0 = p.rest_density_kg_m3;
  lists.used = 0;
  for (std::size_t i = begin; i < end; ++i) {
    const float xi = f.x[i], yi = f.y[i], zi = f.z[i];
    NeighbourRange& range = ranges[i];
    range.offset = static_cast<std::uint32_t>(lists.used);
    const std::uint32_t nf = collect(p.grid, fluid_cell_start, f.x.data(), f.y.data(), f.z.data(), xi, yi, zi, h2, lists);
    const std::uint32_t ns =
        st.size() > 0 ? collect(p.grid, st.cell_start.data(), st.x.data(), st.y.data(), st.z.data(), xi, yi, zi, h2, lists) : 0;
    const std::uint32_t nb =
        bv.size() > 0 ? collect(p.grid, bv.cell_start.data(), bv.x.data(), bv.y.data(), bv.z.data(), xi, yi, zi, h2, lists) : 0;
    range.fluid = static_cast<std::uint16_t>(std::min<std::uint32_t>(nf, 65535));
    range.statics = static_cast<std::uint16_t>(std::min<std::uint32_t>(ns, 65535));
    range.bodies = static_cast<std::uint16_t>(std::min<std::uint32_t>(nb, 65535));
    const std::uint32_t* list = lists.indices.data() + range.offset;
    const KernelConstants& k = p.kernel;
    float* distances = lists.distances.data() + range.offset;
    const ShapeSums fluid =
        shape_sums<false>(f.x.data(), f.y.data(), f.z.data(), nullptr, list, distances, nf, xi, yi, zi, k);
    const ShapeSums walls = shape_sums<true>(st.x.data(), st.y.data(), st.z.data(), st.volume.data(), list + nf,
                                             distances + nf, ns, xi, yi, zi, k);
    const ShapeSums bodies = shape_sums<true>(bv.x.data(), bv.y.data(), bv.z.data(), bv.volume.data(), list + nf + ns,
                                              distances + nf + ns, nb, xi, yi, zi, k);
    const float rho = p.kernel.poly6 * (mass * fluid.poly6 + rho0 * (walls.poly6 + bodies.poly6));
    f.density[i] = rho;
    const float volume = mass / rho;
    f.volume[i] = volume;
    const float pressure = p.stiffness * (rho - rho0);
    f.pressure[i] = pressure > 0 ? pressure : 0;
    f.volume_correction[i] = 1.0f / gradient_correction(k, volume, fluid.moment, walls.moment + bodies.moment);
  }
}

HAPFLUID_CLONES
float fluid_force_pass(const SimulationParams& p, FluidParticles& f, const SortedSolids& st, const SortedSolids& bv,
                       std::size_t begin, std::size_t end, const NeighbourLists& lists, const NeighbourRange* ranges) {
  const KernelConstants& k = p.kernel;
  const float gx = static_cast<float>(p.gravity_m_s2.x), gy = static_cast<float>(p.gravity_m_s2.y),
              gz = static_cast<float>(p.gravity_m_s2.z);
  float max_accel2 = 0;
  for (std::size_t i = begin; i < end; ++i) {
    const float xi = f.x[i], yi = f.y[i], zi = f.z[i];
    const float vxi = f.vx[i], vyi = f.vy[i], vzi = f.vz[i];
    const float pi = f.pressure[i], vci = f.volume_correction[i], mui = f.viscosity[i];
    const float pi2c = 2.0f * pi * vci;
    const NeighbourRange& range = ranges[i];
    const std::uint32_t* list = lists.indices.data() + range.offset;
    const float* distances = lists.distances.data() + range.offset;
    const std::uint32_t nf = range.fluid, ns = range.statics;
    Accel a;
    fluid_terms(f, list, distances, nf, xi, yi, zi, vxi, vyi, vzi, pi, vci, mui, k, a);
    solid_terms(st, list + nf, distances + nf, ns, xi, yi, zi, vxi, vyi, vzi, pi2c, mui, k, a);
    solid_terms(bv, list + nf + ns, distances + nf + ns, range.bodies, xi, yi, zi, vxi, vyi, vzi, pi2c, mui, k, a);
    const float inv_rho = 1.0f / f.density[i];  // a = f / m = (V_p / m_p) sum = sum / rho_p
    f.ax[i] = a.x * inv_rho + gx;
    f.ay[i] = a.y * inv_rho + gy;
    f.az[i] = a.z * inv_rho + gz;
    max_accel2 = std::max(max_accel2, f.ax[i] * f.ax[i] + f.ay[i] * f.ay[i] + f.az[i] * f.az[i]);
  }
  return max_accel2;
}

}  // namespace hapfluid::sim::detail
