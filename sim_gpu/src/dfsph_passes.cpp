#include "dfsph_passes.hpp"

#include <algorithm>
#include <cmath>

#include "hapfluid/sim/cubic_kernel.hpp"
#include "hapfluid/sim/neighbour_grid.hpp"
#include "implicit_viscosity.hpp"

namespace hapfluid::sim::detail {
namespace {

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && !defined(__SANITIZE_THREAD__)
#define HAPFLUID_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define HAPFLUID_CLONES
#endif

// Appends the candidates of the cells around (xi, yi, zi) that lie within h: each run of cells
// is copied branch-free (the index is always written, the cursor advances only for a neighbour),
// which vectorises. Returns how many were appended.
std::uint32_t collect(const GridGeometry& g, const std::uint32_t* cell_start, const float* x, const float* y,
                      const float* z, float xi, float yi, float zi, float h2, PairLists& lists) {
  std::uint32_t count = 0;
  for_each_neighbour_run(g, cell_start, xi, yi, zi, [&](std::uint32_t b, std::uint32_t e) {
    if (lists.used + (e - b) > lists.index.size()) lists.reserve(2 * (lists.used + (e - b)) + 4096);
    std::uint32_t* out = lists.index.data() + lists.used;
    std::uint32_t n = 0;
    for (std::uint32_t j = b; j < e; ++j) {
      const float dx = xi - x[j], dy = yi - y[j], dz = zi - z[j];
      out[n] = j;
      n += (dx * dx + dy * dy + dz * dz < h2) ? 1u : 0u;
    }
    lists.used += n;
    count += n;
  });
  return count;
}

struct Sums {
  float w = 0, gx = 0, gy = 0, gz = 0, g2 = 0;
};

// Kernel values and gradients of n listed pairs, scaled by the neighbour's volume (one volume
// for all fluid particles, Psi_b for solids); returns their sums.
template <bool kPerParticleVolume>
inline Sums pair_kernels(const float* x, const float* y, const float* z, const float* volume, float fluid_volume,
                         const std::uint32_t* list, std::uint32_t n, float xi, float yi, float zi, const CubicKernel& k,
                         float* gx, float* gy, float* gz, float* w) {
  float sw = 0, sx = 0, sy = 0, sz = 0, s2 = 0;
#pragma omp simd reduction(+ : sw, sx, sy, sz, s2)
  for (std::uint32_t q = 0; q < n; ++q) {
    const std::uint32_t j = list[q];
    const float dx = xi - x[j], dy = yi - y[j], dz = zi - z[j];
    const float r = std::sqrt(dx * dx + dy * dy + dz * dz);
    const float v = kPerParticleVolume ? volume[j] : fluid_volume;
    const float wq = v * cubic_w(k, r);
    const float g = v * cubic_grad_over_r(k, r);
    const float ax = g * dx, ay = g * dy, az = g * dz;
    gx[q] = ax, gy[q] = ay, gz[q] = az, w[q] = wq;
    sw += wq, sx += ax, sy += ay, sz += az, s2 += ax * ax + ay * ay + az * az;
  }
  return {sw, sx, sy, sz, s2};
}

inline std::uint16_t clamp16(std::uint32_t n) { return static_cast<std::uint16_t>(std::min<std::uint32_t>(n, 65535)); }

}  // namespace

void PairLists::reserve(std::size_t n) {
  if (n <= index.size()) return;
  index.resize(n);
  gx.resize(n), gy.resize(n), gz.resize(n), w.resize(n);
}

void DfsphFields::resize(std::size_t n) {
  for (auto* v : {&density_hat, &factor, &solid_gx, &solid_gy, &solid_gz, &stiffness_step,
                  &density_stiffness, &divergence_stiffness, &visc_bx, &visc_by, &visc_bz, &visc_inv_diag_x,
                  &visc_inv_diag_y, &visc_inv_diag_z, &cg_rx, &cg_ry, &cg_rz, &cg_px, &cg_py, &cg_pz, &cg_ax, &cg_ay,
                  &cg_az, &visc_wall_x, &visc_wall_y, &visc_wall_z})
    v->assign(n, 0.0f);
  neighbours.assign(n, 0);
}

HAPFLUID_CLONES
void build_pairs(const SimulationParams& p, const FluidParticles& f, const std::uint32_t* fluid_cell_start,
                 const SortedSolids& st, const SortedSolids& bv, const WallMap& walls, std::size_t begin,
                 std::size_t end, PairLists& lists, PairRange* ranges, DfsphFields& out) {
  const CubicKernel& k = p.incompressible.kernel;
  const float h2 = k.h2;
  const float fluid_volume = p.fluid_particle_mass_kg / p.rest_density_kg_m3;
  // A factor denominator this small means a particle with (almost) no neighbours: it gets no
  // pressure rather than a division by zero.
  const float tiny = 1e-6f / h2;
  lists.used = 0;
  for (std::size_t i = begin; i < end; ++i) {
    const float xi = f.x[i], yi = f.y[i], zi = f.z[i];
    PairRange& r = ranges[i];
    r.offset = static_cast<std::uint32_t>(lists.used);
    const std::uint32_t nf = collect(p.grid, fluid_cell_start, f.x.data(), f.y.data(), f.z.data(), xi, yi, zi, h2, lists);
    const std::uint32_t ns =
        st.size() > 0 ? collect(p.grid, st.cell_start.data(), st.x.data(), st.y.data(), st.z.data(), xi, yi, zi, h2, lists) : 0;
    const std::uint32_t nb =
        bv.size() > 0 ? collect(p.grid, bv.cell_start.data(), bv.x.data(), bv.y.data(), bv.z.data(), xi, yi, zi, h2, lists) : 0;
    r.fluid = clamp16(nf), r.statics = clamp16(ns), r.bodies = clamp16(nb);
    const std::uint32_t o = r.offset;
    const std::uint32_t* list = lists.index.data();
    float *gx = lists.gx.data(), *gy = lists.gy.data(), *gz = lists.gz.data(), *w = lists.w.data();
    const Sums sf = pair_kernels<false>(f.x.data(), f.y.data(), f.z.data(), nullptr, fluid_volume, list + o, nf, xi, yi, zi,
                                        k, gx + o, gy + o, gz + o, w + o);
    const Sums ss = pair_kernels<true>(st.x.data(), st.y.data(), st.z.data(), st.volume.data(), 0, list + o + nf, ns, xi, yi,
                                       zi, k, gx + o + nf, gy + o + nf, gz + o + nf, w + o + nf);
    const std::uint32_t ob = o + nf + ns;
    const Sums sb = pair_kernels<true>(bv.x.data(), bv.y.data(), bv.z.data(), bv.volume.data(), 0, list + ob, nb, xi, yi, zi,
                                       k, gx + ob, gy + ob, gz + ob, w + ob);
    float wall_share = 0, wx = 0, wy = 0, wz = 0;
    walls.sample(xi, yi, zi, wall_share, wx, wy, wz);
    out.density_hat[i] = sf.w + ss.w + sb.w + wall_share;
    // The density response to the particle's own stiffness k: it moves by -dt^2 k T (T the sum of
    // all its pair gradients, solids and walls included) and pushes each fluid neighbour by
    // dt^2 k g_ij, so d(rho/rho0) = -dt^2 k (|T|^2 + sum_fluid |g_ij|^2).
    const float sx = ss.gx + sb.gx + wx, sy = ss.gy + sb.gy + wy, sz = ss.gz + sb.gz + wz;
    const float tx = sf.gx + sx, ty = sf.gy + sy, tz = sf.gz + sz;
    const float denominator = tx * tx + ty * ty + tz * tz + sf.g2;
    out.factor[i] = denominator > tiny ? 1.0f / denominator : 0.0f;
    out.solid_gx[i] = sx, out.solid_gy[i] = sy, out.solid_gz[i] = sz;
    out.neighbours[i] = clamp16(nf + ns + nb);
  }
}

HAPFLUID_CLONES
void density_rate(const FluidParticles& f, const SortedSolids& bodies, const DfsphFields& d, const PairLists& lists,
                  const PairRange* ranges, std::size_t begin, std::size_t end, float* rate) {
  const float *vx = f.vx.data(), *vy = f.vy.data(), *vz = f.vz.data();
  const float *bx = bodies.vx.data(), *by = bodies.vy.data(), *bz = bodies.vz.data();
  const std::uint32_t* list = lists.index.data();
  const float *gx = lists.gx.data(), *gy = lists.gy.data(), *gz = lists.gz.data();
  for (std::size_t i = begin; i < end; ++i) {
    const PairRange& r = ranges[i];
    const float vxi = vx[i], vyi = vy[i], vzi = vz[i];
    float s = 0;
    const std::uint32_t o = r.offset, n = r.fluid;
#pragma omp simd reduction(+ : s)
    for (std::uint32_t q = o; q < o + n; ++q) {
      const std::uint32_t j = list[q];
      s += gx[q] * (vxi - vx[j]) + gy[q] * (vyi - vy[j]) + gz[q] * (vzi - vz[j]);
    }
    // The body particles' flux, from their velocities now: a solve coupled to the bodies moves them.
    float flux = 0;
    for (std::uint32_t q = o + n + r.statics; q < o + n + r.statics + r.bodies; ++q) {
      const std::uint32_t j = list[q];
      flux += gx[q] * bx[j] + gy[q] * by[j] + gz[q] * bz[j];
    }
    rate[i] = s + vxi * d.solid_gx[i] + vyi * d.solid_gy[i] + vzi * d.solid_gz[i] - flux;
  }
}

HAPFLUID_CLONES
void apply_stiffness(FluidParticles& f, const DfsphFields& d, const PairLists& lists, const PairRange* ranges,
                     std::size_t begin, std::size_t end, float dt) {
  const float* k = d.stiffness_step.data();
  const std::uint32_t* list = lists.index.data();
  const float *gx = lists.gx.data(), *gy = lists.gy.data(), *gz = lists.gz.data();
  for (std::size_t i = begin; i < end; ++i) {
    const PairRange& r = ranges[i];
    const float ki = k[i];
    float ax = 0, ay = 0, az = 0;
    const std::uint32_t o = r.offset, n = r.fluid;
#pragma omp simd reduction(+ : ax, ay, az)
    for (std::uint32_t q = o; q < o + n; ++q) {
      const float kij = ki + k[list[q]];
      ax += kij * gx[q], ay += kij * gy[q], az += kij * gz[q];
    }
    f.vx[i] -= dt * (ax + ki * d.solid_gx[i]);
    f.vy[i] -= dt * (ay + ki * d.solid_gy[i]);
    f.vz[i] -= dt * (az + ki * d.solid_gz[i]);
  }
}

HAPFLUID_CLONES
void non_pressure_accelerations(const SimulationParams& p, FluidParticles& f, const DfsphFields& d,
                                const PairLists& lists, const PairRange* ranges, std::size_t begin, std::size_t end,
                                float dt) {
  const float xsph = p.incompressible.xsph_fraction / dt;
  const float gx0 = static_cast<float>(p.gravity_m_s2.x), gy0 = static_cast<float>(p.gravity_m_s2.y),
              gz0 = static_cast<float>(p.gravity_m_s2.z);
  const float *vx = f.vx.data(), *vy = f.vy.data(), *vz = f.vz.data();
  const float* rho = d.density_hat.data();
  const std::uint32_t* list = lists.index.data();
  const float* w = lists.w.data();
  for (std::size_t i = begin; i < end; ++i) {
    const PairRange& r = ranges[i];
    const float vxi = vx[i], vyi = vy[i], vzi = vz[i];
    float sx = 0, sy = 0, sz = 0;
    const std::uint32_t o = r.offset, n = r.fluid;
    if (xsph > 0) {
#pragma omp simd reduction(+ : sx, sy, sz)
      for (std::uint32_t q = o; q < o + n; ++q) {
        const std::uint32_t j = list[q];
        const float ws = w[q] / rho[j];
        sx -= ws * (vxi - vx[j]), sy -= ws * (vyi - vy[j]), sz -= ws * (vzi - vz[j]);
      }
    }
    f.ax[i] = gx0 + xsph * sx;
    f.ay[i] = gy0 + xsph * sy;
    f.az[i] = gz0 + xsph * sz;
  }
}

HAPFLUID_CLONES
void body_fluid_forces(const SimulationParams& p, const FluidParticles& f, const std::uint32_t* fluid_cell_start,
                       const DfsphFields& d, BodyForcePart part, BodyParticles& bp, std::size_t begin, std::size_t end) {
  const bool pressure = part == BodyForcePart::pressure;
  const CubicKernel& k = p.incompressible.kernel;
  const float mass = p.fluid_particle_mass_kg, inv_rho0 = 1.0f / p.rest_density_kg_m3, eps2 = 0.01f * k.h2;
  for (std::size_t b = begin; b < end; ++b) {
    const float xb = bp.x[b], yb = bp.y[b], zb = bp.z[b], vxb = bp.vx[b], vyb = bp.vy[b], vzb = bp.vz[b];
    const float psi = bp.volume[b], mub = bp.viscosity[b];
    float fx = 0, fy = 0, fz = 0;
    for_each_neighbour_run(p.grid, fluid_cell_start, xb, yb, zb, [&](std::uint32_t s, std::uint32_t e) {
      for (std::uint32_t j = s; j < e; ++j) {
        const float dx = f.x[j] - xb, dy = f.y[j] - yb, dz = f.z[j] - zb;
        const float r2 = dx * dx + dy * dy + dz * dz;
        if (r2 >= k.h2) continue;
        const float g = psi * cubic_grad_over_r(k, std::sqrt(r2));
        float c;
        if (pressure) {
          // The opposite of the fluid's boundary term, with this step's stiffness of both solves.
          c = mass * (d.density_stiffness[j] + d.divergence_stiffness[j]) * g;
        } else {
          const float pi = ((f.vx[j] - vxb) * dx + (f.vy[j] - vyb) * dy + (f.vz[j] - vzb) * dz) / (r2 + eps2);
          c = -mass * kLaplacianFactor * 0.5f * (f.viscosity[j] + mub) * inv_rho0 * pi * g;
        }
        fx += c * dx, fy += c * dy, fz += c * dz;
      }
    });
    if (pressure) {
      bp.fx[b] += fx, bp.fy[b] += fy, bp.fz[b] += fz;
    } else {
      bp.fx[b] = fx, bp.fy[b] = fy, bp.fz[b] = fz;
    }
  }
}

}  // namespace hapfluid::sim::detail
