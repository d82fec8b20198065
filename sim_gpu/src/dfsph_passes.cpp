#include "dfsph_passes.hpp"

#include <algorithm>
#include <cmath>

#include "hapfluid/sim/cubic_kernel.hpp"
#include "hapfluid/sim/neighbour_grid.hpp"
#include "implicit_viscosity.hpp"
#include "neighbour_filter.hpp"
#include "simd.hpp"

namespace hapfluid::sim::detail {
namespace {

// Appends the candidates of the cells around (xi, yi, zi) that lie within h to the slot's lists,
// their offsets x_i - x_j to its scratch from `first` on (neighbour_filter.hpp). Returns how many.
std::uint32_t collect(FilterFn filter, const GridGeometry& g, const std::uint32_t* cell_start, const float* x,
                      const float* y, const float* z, float xi, float yi, float zi, float h2, std::uint32_t first,
                      PairLists& lists) {
  std::uint32_t count = 0;
  for_each_neighbour_run(g, cell_start, xi, yi, zi, [&](std::uint32_t b, std::uint32_t e) {
    const std::size_t room = (e - b) + kFilterSlack;
    if (lists.used + room > lists.index.size()) lists.reserve(2 * (lists.used + room) + 4096);
    if (first + count + room > lists.scratch_dx.size()) lists.reserve_scratch(2 * (first + count + room));
    const std::uint32_t at = first + count;
    const std::uint32_t n = filter(x, y, z, b, e, xi, yi, zi, h2,
                                   {lists.index.data() + lists.used, lists.scratch_dx.data() + at,
                                    lists.scratch_dy.data() + at, lists.scratch_dz.data() + at});
    lists.used += n;
    count += n;
  });
  return count;
}

struct Sums {
  V4 g = splat(0);  // x y z: the sum of the pair gradients; w: the sum of the kernel values
  float g2 = 0;     // the sum of the gradients' squares
};

// The unit-volume kernel values and gradients of the n collected pairs, in place of their offsets
// in the scratch (w into scratch_w). Padded to a whole number of 8-wide vectors with pairs beyond
// the support (offset h: W = 0, grad W = 0), so the loop of selects vectorises with no remainder.
HAPFLUID_CLONES
void unit_kernels(PairLists& lists, std::uint32_t n, const CubicKernel& k) {
  float *dxs = lists.scratch_dx.data(), *dys = lists.scratch_dy.data(), *dzs = lists.scratch_dz.data();
  float* ws = lists.scratch_w.data();
  const std::uint32_t padded = (n + 7) & ~7u;
  for (std::uint32_t q = n; q < padded; ++q) dxs[q] = k.h, dys[q] = 0, dzs[q] = 0;
#pragma omp simd
  for (std::uint32_t q = 0; q < padded; ++q) {
    const float dx = dxs[q], dy = dys[q], dz = dzs[q];
    const float r = std::sqrt(dx * dx + dy * dy + dz * dz);
    const float g = cubic_grad_over_r(k, r);
    ws[q] = cubic_w(k, r);
    dxs[q] = g * dx, dys[q] = g * dy, dzs[q] = g * dz;
  }
}

// Packs the unit terms of the pairs [first, first + n) of the scratch, scaled by the neighbour's
// volume (one volume for all fluid particles, Psi_b for solids), into their terms; returns sums.
template <bool kPerParticleVolume>
inline Sums pack_terms(const PairLists& lists, std::uint32_t first, std::uint32_t n, const float* volume,
                       float fluid_volume, const std::uint32_t* list, Packed4* term) {
  const float *dxs = lists.scratch_dx.data(), *dys = lists.scratch_dy.data(), *dzs = lists.scratch_dz.data();
  const float* ws = lists.scratch_w.data();
  Sums s;
  for (std::uint32_t q = 0; q < n; ++q) {
    const std::uint32_t u = first + q;
    const V4 t = splat(kPerParticleVolume ? volume[list[q]] : fluid_volume) * V4{dxs[u], dys[u], dzs[u], ws[u]};
    store(term[q], t);
    s.g += t;
    s.g2 += dot3(t, t);
  }
  return s;
}

inline std::uint16_t clamp16(std::uint32_t n) { return static_cast<std::uint16_t>(std::min<std::uint32_t>(n, 65535)); }

}  // namespace

void PairLists::reserve_scratch(std::size_t n) {
  if (n <= scratch_dx.size()) return;
  scratch_dx.resize(n), scratch_dy.resize(n), scratch_dz.resize(n), scratch_w.resize(n);
}

void PairLists::reserve(std::size_t n) {
  if (n <= index.size()) return;
  index.resize(n);
  term.resize(n);
}

void DfsphFields::resize(std::size_t n) {
  for (auto* v : {&density_hat, &factor, &solid_gx, &solid_gy, &solid_gz, &stiffness_step,
                  &density_stiffness, &divergence_stiffness, &visc_bx, &visc_by, &visc_bz, &visc_inv_diag_x,
                  &visc_inv_diag_y, &visc_inv_diag_z, &cg_rx, &cg_ry, &cg_rz, &cg_px, &cg_py, &cg_pz, &cg_ax, &cg_ay,
                  &cg_az, &visc_wall_x, &visc_wall_y, &visc_wall_z})
    v->assign(n, 0.0f);
  position.assign(n, Packed4{});
  velocity.assign(n, Packed4{});
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
  const FilterFn filter = neighbour_filter();
  lists.used = 0;
  for (std::size_t i = begin; i < end; ++i) {
    const float xi = f.x[i], yi = f.y[i], zi = f.z[i];
    PairRange& r = ranges[i];
    r.offset = static_cast<std::uint32_t>(lists.used);
    const std::uint32_t nf =
        collect(filter, p.grid, fluid_cell_start, f.x.data(), f.y.data(), f.z.data(), xi, yi, zi, h2, 0, lists);
    const std::uint32_t ns = st.size() > 0 ? collect(filter, p.grid, st.cell_start.data(), st.x.data(), st.y.data(),
                                                     st.z.data(), xi, yi, zi, h2, nf, lists)
                                           : 0;
    const std::uint32_t nb = bv.size() > 0 ? collect(filter, p.grid, bv.cell_start.data(), bv.x.data(), bv.y.data(),
                                                     bv.z.data(), xi, yi, zi, h2, nf + ns, lists)
                                           : 0;
    r.fluid = clamp16(nf), r.statics = clamp16(ns), r.bodies = clamp16(nb);
    const std::uint32_t o = r.offset;
    const std::uint32_t* list = lists.index.data();
    Packed4* term = lists.term.data();
    unit_kernels(lists, nf + ns + nb, k);
    const Sums sf = pack_terms<false>(lists, 0, nf, nullptr, fluid_volume, list + o, term + o);
    const Sums ss = pack_terms<true>(lists, nf, ns, st.volume.data(), 0, list + o + nf, term + o + nf);
    const std::uint32_t ob = o + nf + ns;
    const Sums sb = pack_terms<true>(lists, nf + ns, nb, bv.volume.data(), 0, list + ob, term + ob);
    float wall_share = 0, wx = 0, wy = 0, wz = 0;
    walls.sample(xi, yi, zi, wall_share, wx, wy, wz);
    out.density_hat[i] = sf.g[3] + ss.g[3] + sb.g[3] + wall_share;
    // The density response to the particle's own stiffness k: it moves by -dt^2 k T (T the sum of
    // all its pair gradients, solids and walls included) and pushes each fluid neighbour by
    // dt^2 k g_ij, so d(rho/rho0) = -dt^2 k (|T|^2 + sum_fluid |g_ij|^2).
    const float sx = ss.g[0] + sb.g[0] + wx, sy = ss.g[1] + sb.g[1] + wy, sz = ss.g[2] + sb.g[2] + wz;
    const float tx = sf.g[0] + sx, ty = sf.g[1] + sy, tz = sf.g[2] + sz;
    const float denominator = tx * tx + ty * ty + tz * tz + sf.g2;
    out.factor[i] = denominator > tiny ? 1.0f / denominator : 0.0f;
    out.solid_gx[i] = sx, out.solid_gy[i] = sy, out.solid_gz[i] = sz;
    out.neighbours[i] = clamp16(nf + ns + nb);
  }
}

HAPFLUID_CLONES
void density_rate(const SortedSolids& bodies, const DfsphFields& d, const PairLists& lists, const PairRange* ranges,
                  std::size_t begin, std::size_t end, float* rate, bool body_pairs) {
  const Packed4* v = d.velocity.data();
  const float *bx = bodies.vx.data(), *by = bodies.vy.data(), *bz = bodies.vz.data();
  const std::uint32_t* list = lists.index.data();
  const Packed4* term = lists.term.data();
  for (std::size_t i = begin; i < end; ++i) {
    const PairRange& r = ranges[i];
    const V4 vi = load(v[i]);
    V4 s = splat(0);
    const std::uint32_t o = r.offset, n = r.fluid;
    for (std::uint32_t q = o; q < o + n; ++q) s += load(term[q]) * (vi - load(v[list[q]]));
    // The body particles' flux, from their velocities now: a solve coupled to the bodies moves them.
    float flux = 0;
    const std::uint32_t body_end = body_pairs ? o + n + r.statics + r.bodies : 0;
    for (std::uint32_t q = o + n + r.statics; q < body_end; ++q) {
      const std::uint32_t j = list[q];
      flux += term[q].x * bx[j] + term[q].y * by[j] + term[q].z * bz[j];
    }
    rate[i] = s[0] + s[1] + s[2] + dot3(vi, V4{d.solid_gx[i], d.solid_gy[i], d.solid_gz[i], 0.0f}) - flux;
  }
}

HAPFLUID_CLONES
void apply_stiffness(DfsphFields& d, const PairLists& lists, const PairRange* ranges, std::size_t begin,
                     std::size_t end, float dt) {
  const float* k = d.stiffness_step.data();
  const std::uint32_t* list = lists.index.data();
  const Packed4* term = lists.term.data();
  Packed4* v = d.velocity.data();
  for (std::size_t i = begin; i < end; ++i) {
    const PairRange& r = ranges[i];
    const float ki = k[i];
    V4 a = splat(ki) * V4{d.solid_gx[i], d.solid_gy[i], d.solid_gz[i], 0.0f};
    const std::uint32_t o = r.offset, n = r.fluid;
    for (std::uint32_t q = o; q < o + n; ++q) a += splat(ki + k[list[q]]) * load(term[q]);
    a[3] = 0.0f;
    store(v[i], load(v[i]) - splat(dt) * a);
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
  const Packed4* term = lists.term.data();
  for (std::size_t i = begin; i < end; ++i) {
    const PairRange& r = ranges[i];
    const float vxi = vx[i], vyi = vy[i], vzi = vz[i];
    float sx = 0, sy = 0, sz = 0;
    const std::uint32_t o = r.offset, n = r.fluid;
    if (xsph > 0) {
      for (std::uint32_t q = o; q < o + n; ++q) {
        const std::uint32_t j = list[q];
        const float ws = term[q].w / rho[j];
        sx -= ws * (vxi - vx[j]), sy -= ws * (vyi - vy[j]), sz -= ws * (vzi - vz[j]);
      }
    }
    f.ax[i] = gx0 + xsph * sx;
    f.ay[i] = gy0 + xsph * sy;
    f.az[i] = gz0 + xsph * sz;
  }
}

HAPFLUID_CLONES
void body_pair_forces(const SimulationParams& p, const FluidParticles& f, const DfsphFields& d, const SortedSolids& bodies,
                      BodyForcePart part, const PairLists& lists, const PairRange* ranges, std::size_t begin,
                      std::size_t end, float* sums) {
  const float mass = p.fluid_particle_mass_kg, eps2 = 0.01f * p.incompressible.kernel.h2;
  const float viscous_scale = -mass * kLaplacianFactor * 0.5f / p.rest_density_kg_m3;
  std::fill(sums, sums + 3 * bodies.size(), 0.0f);
  const std::uint32_t* list = lists.index.data();
  const Packed4* term = lists.term.data();
  for (std::size_t i = begin; i < end; ++i) {
    const PairRange& r = ranges[i];
    if (r.bodies == 0) continue;
    const std::uint32_t first = r.offset + r.fluid + r.statics;
    for (std::uint32_t q = first; q < first + r.bodies; ++q) {
      const std::uint32_t b = list[q];
      float c;
      if (part == BodyForcePart::pressure) {
        // The opposite of the fluid's boundary term, with this step's stiffness of both solves.
        c = mass * (d.density_stiffness[i] + d.divergence_stiffness[i]);
      } else {
        const float dx = f.x[i] - bodies.x[b], dy = f.y[i] - bodies.y[b], dz = f.z[i] - bodies.z[b];
        const float pi = ((f.vx[i] - bodies.vx[b]) * dx + (f.vy[i] - bodies.vy[b]) * dy + (f.vz[i] - bodies.vz[b]) * dz) /
                         (dx * dx + dy * dy + dz * dz + eps2);
        c = viscous_scale * (f.viscosity[i] + bodies.viscosity[b]) * pi;
      }
      sums[3 * b] += c * term[q].x, sums[3 * b + 1] += c * term[q].y, sums[3 * b + 2] += c * term[q].z;
    }
  }
}

}  // namespace hapfluid::sim::detail
