#include "body_contacts.hpp"

#include <algorithm>
#include <cmath>

#include "hapfluid/sim/contact_damping.hpp"

namespace hapfluid::sim::detail {

void BodyReach::resize(std::size_t bodies) {
  lo_.assign(3 * bodies, 0.0f);
  hi_.assign(3 * bodies, 0.0f);
  near_.assign(bodies, 0);
}

void BodyReach::update(const BodyParticles& bp, float reach) {
  const std::size_t bodies = near_.size();
  std::fill(lo_.begin(), lo_.end(), 1e30f);
  std::fill(hi_.begin(), hi_.end(), -1e30f);
  for (std::size_t i = 0; i < bp.size(); ++i) {
    const std::size_t b = 3 * static_cast<std::size_t>(bp.body[i]);
    const float at[3] = {bp.x[i], bp.y[i], bp.z[i]};
    // A position that is not finite spans everything: the search stays on.
    const bool finite = std::isfinite(at[0]) && std::isfinite(at[1]) && std::isfinite(at[2]);
    for (int a = 0; a < 3; ++a) {
      lo_[b + a] = std::min(lo_[b + a], finite ? at[a] : -1e30f);
      hi_[b + a] = std::max(hi_[b + a], finite ? at[a] : 1e30f);
    }
  }
  auto apart = [&](std::size_t a, std::size_t b) {
    for (int k = 0; k < 3; ++k)
      if (lo_[3 * a + k] > hi_[3 * b + k] + reach || lo_[3 * b + k] > hi_[3 * a + k] + reach) return true;
    return false;
  };
  for (std::size_t a = 0; a < bodies; ++a) {
    near_[a] = 0;
    for (std::size_t b = 0; b < bodies && !near_[a]; ++b) near_[a] = b != a && !apart(a, b) ? 1 : 0;
  }
}

void body_contact_pressure(const SimulationParams& p, const SortedSolids& st, SortedSolids& bv, BodyParticles& bodies,
                           const BodyReach& reach, std::size_t begin, std::size_t end) {
  const KernelConstants& k = p.kernel;
  for (std::size_t q = begin; q < end; ++q) {
    const float xi = bv.x[q], yi = bv.y[q], zi = bv.z[q];
    const std::int32_t own = bv.body[q];
    float sum = 0;
    for_each_neighbour_run(p.grid, st.cell_start.data(), xi, yi, zi, [&](std::uint32_t b, std::uint32_t e) {
      for (std::uint32_t j = b; j < e; ++j) {
        const float dx = xi - st.x[j], dy = yi - st.y[j], dz = zi - st.z[j];
        sum += st.volume[j] * poly6_shape(k, dx * dx + dy * dy + dz * dz);
      }
    });
    if (reach.near_other(own))
      for_each_neighbour_run(p.grid, bv.cell_start.data(), xi, yi, zi, [&](std::uint32_t b, std::uint32_t e) {
        for (std::uint32_t j = b; j < e; ++j) {
          if (bv.body[j] == own) continue;
          const float dx = xi - bv.x[j], dy = yi - bv.y[j], dz = zi - bv.z[j];
          sum += bv.volume[j] * poly6_shape(k, dx * dx + dy * dy + dz * dz);
        }
      });
    const float pressure = p.stiffness * p.rest_density_kg_m3 * k.poly6 * sum;
    bv.pressure[q] = pressure;
    bodies.pressure[bv.source[q]] = pressure;
  }
}

bool body_contact_forces(const SimulationParams& p, const SortedSolids& st, const SortedSolids& bv, BodyParticles& bp,
                         const BodyReach& reach, std::size_t begin, std::size_t end) {
  const KernelConstants& k = p.kernel;
  const float damping_scale = p.contact_damping_pa_s;
  bool touching = false;
  // One pair with another solid: its contact pressure pj (the static solids carry none of their
  // own and mirror pb), damping and eq. 9.
  auto pair = [&](const SortedSolids& s, std::uint32_t j, float xi, float yi, float zi, float vxi, float vyi, float vzi,
                  float pb, float pj, float mui, float& cx, float& cy, float& cz) {
    const float dx = xi - s.x[j], dy = yi - s.y[j], dz = zi - s.z[j];
    const float r2 = dx * dx + dy * dy + dz * dz;
    if (r2 >= k.h2 || r2 <= 0) return;
    touching = true;
    const float r = std::sqrt(r2);
    const float hr = k.h - r;
    const float dvx = s.vx[j] - vxi, dvy = s.vy[j] - vyi, dvz = s.vz[j] - vzi;
    const float damping = contact_viscous_pressure(damping_scale, -(dvx * dx + dvy * dy + dvz * dz), r2, k.h2);
    const float pterm = -s.volume[j] * (pb + pj + damping) * spiky_grad_factor(k, r, hr);
    const float vterm = s.volume[j] * 0.5f * (s.viscosity[j] + mui) * viscosity_laplacian_of(k, hr);
    cx += pterm * dx + vterm * dvx;
    cy += pterm * dy + vterm * dvy;
    cz += pterm * dz + vterm * dvz;
  };
  for (std::size_t i = begin; i < end; ++i) {
    const float xi = bp.x[i], yi = bp.y[i], zi = bp.z[i];
    const float vxi = bp.vx[i], vyi = bp.vy[i], vzi = bp.vz[i];
    const float vol = bp.volume[i], mui = bp.viscosity[i], pb = bp.pressure[i];
    const std::int32_t own = bp.body[i];
    float cx = 0, cy = 0, cz = 0;
    for_each_neighbour_run(p.grid, st.cell_start.data(), xi, yi, zi, [&](std::uint32_t b, std::uint32_t e) {
      for (std::uint32_t j = b; j < e; ++j) pair(st, j, xi, yi, zi, vxi, vyi, vzi, pb, pb, mui, cx, cy, cz);
    });
    if (reach.near_other(own))
      for_each_neighbour_run(p.grid, bv.cell_start.data(), xi, yi, zi, [&](std::uint32_t b, std::uint32_t e) {
        for (std::uint32_t j = b; j < e; ++j)
          if (bv.body[j] != own) pair(bv, j, xi, yi, zi, vxi, vyi, vzi, pb, bv.pressure[j], mui, cx, cy, cz);
      });
    bp.cx[i] = cx * vol;
    bp.cy[i] = cy * vol;
    bp.cz[i] = cz * vol;
  }
  return touching;
}

}  // namespace hapfluid::sim::detail
