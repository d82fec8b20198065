#include "implicit_viscosity.hpp"

#include "simd.hpp"

namespace hapfluid::sim::detail {
namespace {

struct PairTerms {
  float scale;  // dt kLaplacianFactor / 2 / rho0: c_ij = scale (mu_i + mu_j) [2 / (rho_i + rho_j)] / d_ij
  float eps2;   // 0.01 h^2
};

PairTerms terms(const SimulationParams& p, float dt) {
  return {dt * kLaplacianFactor * 0.5f / p.rest_density_kg_m3, 0.01f * p.incompressible.kernel.h2};
}

// Solid neighbours: their velocity into the right-hand side b, their share of the diagonal, and
// (when v_i is given) their share of K v_i.
void solid_terms(const SortedSolids& s, const std::uint32_t* list, const Packed4* term, std::uint32_t n, V4 pi, V4 vi,
                 PairTerms t, V4& b, V4& diagonal, V4& product) {
  const float mui = pi[3];
  for (std::uint32_t q = 0; q < n; ++q) {
    const std::uint32_t j = list[q];
    const V4 d = pi - V4{s.x[j], s.y[j], s.z[j], 0.0f};
    const V4 g = load(term[q]);
    const float c = t.scale * (mui + s.viscosity[j]) / (dot3(d, d) + t.eps2);
    b -= splat(c * dot3(V4{s.vx[j], s.vy[j], s.vz[j], 0.0f}, d)) * g;
    diagonal -= splat(c) * d * g;
    product += splat(c * dot3(vi, d)) * g;
  }
}

void solid_product(const SortedSolids& s, const std::uint32_t* list, const Packed4* term, std::uint32_t n, V4 pi,
                   V4 vi, PairTerms t, V4& product) {
  const float mui = pi[3];
  for (std::uint32_t q = 0; q < n; ++q) {
    const std::uint32_t j = list[q];
    const V4 d = pi - V4{s.x[j], s.y[j], s.z[j], 0.0f};
    const float c = t.scale * (mui + s.viscosity[j]) / (dot3(d, d) + t.eps2);
    product += splat(c * dot3(vi, d)) * load(term[q]);
  }
}

}  // namespace

HAPFLUID_CLONES
void viscosity_rhs(const SimulationParams& p, const SortedSolids& st, const SortedSolids& bv, const WallMap& walls,
                   const PairLists& lists, const PairRange* ranges, std::size_t begin, std::size_t end, float dt,
                   DfsphFields& d) {
  const PairTerms t = terms(p, dt);
  const std::uint32_t* list = lists.index.data();
  const Packed4* term = lists.term.data();
  const Packed4 *position = d.position.data(), *velocity = d.velocity.data();
  for (std::size_t i = begin; i < end; ++i) {
    const PairRange& r = ranges[i];
    const V4 pi = load(position[i]), vi = load(velocity[i]);
    const float mui = pi[3], rhoi = vi[3];
    V4 diagonal = splat(0), product = splat(0), b{d.visc_bx[i], d.visc_by[i], d.visc_bz[i], 0.0f};
    const std::uint32_t o = r.offset, n = r.fluid;
    for (std::uint32_t q = o; q < o + n; ++q) {
      const std::uint32_t j = list[q];
      const V4 pj = load(position[j]), vj = load(velocity[j]);
      const V4 dx = pi - pj;
      const V4 g = load(term[q]);
      const float c = 2.0f * t.scale * (mui + pj[3]) / ((rhoi + vj[3]) * (dot3(dx, dx) + t.eps2));
      diagonal -= splat(c) * dx * g;
      product += splat(c * dot3(vi - vj, dx)) * g;
    }
    solid_terms(st, list + o + n, term + o + n, r.statics, pi, vi, t, b, diagonal, product);
    const std::uint32_t ob = o + n + r.statics;
    solid_terms(bv, list + ob, term + ob, r.bodies, pi, vi, t, b, diagonal, product);
    float wx = 0, wy = 0, wz = 0;
    walls.friction(pi[0], pi[1], pi[2], wx, wy, wz);
    const float cw = t.scale * (mui + p.fluid_viscosity_pa_s);
    const V4 wall{cw * wx, cw * wy, cw * wz, 0.0f};
    d.visc_wall_x[i] = wall[0], d.visc_wall_y[i] = wall[1], d.visc_wall_z[i] = wall[2];
    // The diagonal is 1 - dt sum c x_a g_a / d (each term >= 0 subtracted) plus the walls'.
    const V4 diag = splat(1.0f) + diagonal + wall;
    const V4 kv = vi - product + wall * vi;
    d.visc_bx[i] = b[0], d.visc_by[i] = b[1], d.visc_bz[i] = b[2];
    d.visc_inv_diag_x[i] = 1.0f / diag[0], d.visc_inv_diag_y[i] = 1.0f / diag[1], d.visc_inv_diag_z[i] = 1.0f / diag[2];
    d.cg_ax[i] = kv[0], d.cg_ay[i] = kv[1], d.cg_az[i] = kv[2];
  }
}

HAPFLUID_CLONES
void viscosity_apply(const SimulationParams& p, const SortedSolids& st, const SortedSolids& bv, const DfsphFields& d,
                     const PairLists& lists, const PairRange* ranges, std::size_t begin, std::size_t end, float dt,
                     const float* vx, const float* vy, const float* vz, float* ox, float* oy, float* oz) {
  const PairTerms t = terms(p, dt);
  const std::uint32_t* list = lists.index.data();
  const Packed4* term = lists.term.data();
  const Packed4* position = d.position.data();
  const float* rho = d.density_hat.data();
  for (std::size_t i = begin; i < end; ++i) {
    const PairRange& r = ranges[i];
    const V4 pi = load(position[i]), vi{vx[i], vy[i], vz[i], 0.0f};
    const float mui = pi[3], rhoi = rho[i];
    V4 product = splat(0);
    const std::uint32_t o = r.offset, n = r.fluid;
    for (std::uint32_t q = o; q < o + n; ++q) {
      const std::uint32_t j = list[q];
      const V4 pj = load(position[j]);
      const V4 dx = pi - pj;
      const float c = 2.0f * t.scale * (mui + pj[3]) / ((rhoi + rho[j]) * (dot3(dx, dx) + t.eps2));
      product += splat(c * dot3(vi - V4{vx[j], vy[j], vz[j], 0.0f}, dx)) * load(term[q]);
    }
    solid_product(st, list + o + n, term + o + n, r.statics, pi, vi, t, product);
    const std::uint32_t ob = o + n + r.statics;
    solid_product(bv, list + ob, term + ob, r.bodies, pi, vi, t, product);
    ox[i] = vi[0] - product[0] + d.visc_wall_x[i] * vi[0];
    oy[i] = vi[1] - product[1] + d.visc_wall_y[i] * vi[1];
    oz[i] = vi[2] - product[2] + d.visc_wall_z[i] * vi[2];
  }
}

}  // namespace hapfluid::sim::detail
