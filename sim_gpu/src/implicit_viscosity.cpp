#include "implicit_viscosity.hpp"

namespace hapfluid::sim::detail {
namespace {

struct PairTerms {
  float inv_rho0, eps2;
};

PairTerms terms(const SimulationParams& p) {
  return {1.0f / p.rest_density_kg_m3, 0.01f * p.incompressible.kernel.h2};
}

// Solid neighbours: their velocity into the right-hand side, their share of the diagonal.
void solid_terms(const SortedSolids& s, const std::uint32_t* list, const float* gx, const float* gy, const float* gz,
                 std::uint32_t n, float xi, float yi, float zi, float mui, PairTerms t, float dt, float& bx, float& by,
                 float& bz, float& dx_, float& dy_, float& dz_) {
  for (std::uint32_t q = 0; q < n; ++q) {
    const std::uint32_t j = list[q];
    const float dx = xi - s.x[j], dy = yi - s.y[j], dz = zi - s.z[j];
    const float c = dt * kLaplacianFactor * 0.5f * (mui + s.viscosity[j]) * t.inv_rho0 / (dx * dx + dy * dy + dz * dz + t.eps2);
    const float vb = s.vx[j] * dx + s.vy[j] * dy + s.vz[j] * dz;
    bx -= c * vb * gx[q], by -= c * vb * gy[q], bz -= c * vb * gz[q];
    dx_ -= c * dx * gx[q], dy_ -= c * dy * gy[q], dz_ -= c * dz * gz[q];
  }
}

void solid_apply(const SortedSolids& s, const std::uint32_t* list, const float* gx, const float* gy, const float* gz,
                 std::uint32_t n, float xi, float yi, float zi, float vxi, float vyi, float vzi, float mui, PairTerms t,
                 float dt, float& ax, float& ay, float& az) {
  for (std::uint32_t q = 0; q < n; ++q) {
    const std::uint32_t j = list[q];
    const float dx = xi - s.x[j], dy = yi - s.y[j], dz = zi - s.z[j];
    const float c = dt * kLaplacianFactor * 0.5f * (mui + s.viscosity[j]) * t.inv_rho0 *
                    (vxi * dx + vyi * dy + vzi * dz) / (dx * dx + dy * dy + dz * dz + t.eps2);
    ax += c * gx[q], ay += c * gy[q], az += c * gz[q];
  }
}

}  // namespace

void viscosity_rhs(const SimulationParams& p, const FluidParticles& f, const SortedSolids& st, const SortedSolids& bv,
                   const WallMap& walls, const PairLists& lists, const PairRange* ranges, std::size_t begin,
                   std::size_t end, float dt, DfsphFields& d) {
  const PairTerms t = terms(p);
  const std::uint32_t* list = lists.index.data();
  const float *gx = lists.gx.data(), *gy = lists.gy.data(), *gz = lists.gz.data();
  const float* rho = d.density_hat.data();
  for (std::size_t i = begin; i < end; ++i) {
    const PairRange& r = ranges[i];
    const float xi = f.x[i], yi = f.y[i], zi = f.z[i], mui = f.viscosity[i];
    float bx = f.vx[i], by = f.vy[i], bz = f.vz[i];
    float dgx = 1, dgy = 1, dgz = 1;  // the diagonal: 1 - dt sum c x_a g_a / d (each term >= 0 subtracted)
    const std::uint32_t o = r.offset, n = r.fluid;
    for (std::uint32_t q = o; q < o + n; ++q) {
      const std::uint32_t j = list[q];
      const float dx = xi - f.x[j], dy = yi - f.y[j], dz = zi - f.z[j];
      const float c = dt * kLaplacianFactor * 0.5f * (mui + f.viscosity[j]) * t.inv_rho0 * 2.0f / (rho[i] + rho[j]) /
                      (dx * dx + dy * dy + dz * dz + t.eps2);
      dgx -= c * dx * gx[q], dgy -= c * dy * gy[q], dgz -= c * dz * gz[q];
    }
    solid_terms(st, list + o + n, gx + o + n, gy + o + n, gz + o + n, r.statics, xi, yi, zi, mui, t, dt, bx, by, bz, dgx,
                dgy, dgz);
    const std::uint32_t ob = o + n + r.statics;
    solid_terms(bv, list + ob, gx + ob, gy + ob, gz + ob, r.bodies, xi, yi, zi, mui, t, dt, bx, by, bz, dgx, dgy, dgz);
    float wx = 0, wy = 0, wz = 0;
    walls.friction(xi, yi, zi, wx, wy, wz);
    const float cw = dt * kLaplacianFactor * 0.5f * (mui + p.fluid_viscosity_pa_s) * t.inv_rho0;
    d.visc_wall_x[i] = cw * wx, d.visc_wall_y[i] = cw * wy, d.visc_wall_z[i] = cw * wz;
    dgx += d.visc_wall_x[i], dgy += d.visc_wall_y[i], dgz += d.visc_wall_z[i];
    d.visc_bx[i] = bx, d.visc_by[i] = by, d.visc_bz[i] = bz;
    d.visc_inv_diag_x[i] = 1.0f / dgx, d.visc_inv_diag_y[i] = 1.0f / dgy, d.visc_inv_diag_z[i] = 1.0f / dgz;
  }
}

void viscosity_apply(const SimulationParams& p, const FluidParticles& f, const SortedSolids& st, const SortedSolids& bv,
                     const DfsphFields& d, const PairLists& lists, const PairRange* ranges, std::size_t begin,
                     std::size_t end, float dt, const float* vx, const float* vy, const float* vz, float* ox, float* oy,
                     float* oz) {
  const PairTerms t = terms(p);
  const std::uint32_t* list = lists.index.data();
  const float *gx = lists.gx.data(), *gy = lists.gy.data(), *gz = lists.gz.data();
  const float* rho = d.density_hat.data();
  for (std::size_t i = begin; i < end; ++i) {
    const PairRange& r = ranges[i];
    const float xi = f.x[i], yi = f.y[i], zi = f.z[i], mui = f.viscosity[i];
    const float vxi = vx[i], vyi = vy[i], vzi = vz[i];
    float ax = 0, ay = 0, az = 0;
    const std::uint32_t o = r.offset, n = r.fluid;
#pragma omp simd reduction(+ : ax, ay, az)
    for (std::uint32_t q = o; q < o + n; ++q) {
      const std::uint32_t j = list[q];
      const float dx = xi - f.x[j], dy = yi - f.y[j], dz = zi - f.z[j];
      const float c = dt * kLaplacianFactor * 0.5f * (mui + f.viscosity[j]) * t.inv_rho0 * 2.0f / (rho[i] + rho[j]) *
                      ((vxi - vx[j]) * dx + (vyi - vy[j]) * dy + (vzi - vz[j]) * dz) / (dx * dx + dy * dy + dz * dz + t.eps2);
      ax += c * gx[q], ay += c * gy[q], az += c * gz[q];
    }
    solid_apply(st, list + o + n, gx + o + n, gy + o + n, gz + o + n, r.statics, xi, yi, zi, vxi, vyi, vzi, mui, t, dt, ax,
                ay, az);
    const std::uint32_t ob = o + n + r.statics;
    solid_apply(bv, list + ob, gx + ob, gy + ob, gz + ob, r.bodies, xi, yi, zi, vxi, vyi, vzi, mui, t, dt, ax, ay, az);
    ox[i] = vxi - ax + d.visc_wall_x[i] * vxi, oy[i] = vyi - ay + d.visc_wall_y[i] * vyi,
    oz[i] = vzi - az + d.visc_wall_z[i] * vzi;
  }
}

}  // namespace hapfluid::sim::detail
