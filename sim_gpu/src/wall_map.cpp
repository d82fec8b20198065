#include "hapfluid/sim/wall_map.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include "hapfluid/sim/neighbour_grid.hpp"

namespace hapfluid::sim {
namespace {

constexpr int kTableSize = 513;

// The cubic spline's shape w(q) (W = 8 / (pi h^3) w(r / h)) times q and times q^2, integrated
// from a to 1 in closed form: I(a) = int_a^1 w q dq, J(a) = int_a^1 w q^2 dq, piece by piece
// (6 q^3 - 6 q^2 + 1 up to q = 1/2, 2 (1 - q)^3 beyond).
double inner_q(double q) { return 1.2 * q * q * q * q * q - 1.5 * q * q * q * q + 0.5 * q * q; }
double outer_q(double q) { return q * q - 2 * q * q * q + 1.5 * q * q * q * q - 0.4 * q * q * q * q * q; }
double inner_q2(double q) { return q * q * q * q * q * q - 1.2 * q * q * q * q * q + q * q * q / 3; }
double outer_q2(double q) {
  return 2.0 / 3.0 * q * q * q - 1.5 * q * q * q * q + 1.2 * q * q * q * q * q - q * q * q * q * q * q / 3;
}
double integral_q(double a) {
  if (a >= 1) return 0;
  if (a >= 0.5) return outer_q(1) - outer_q(a);
  return inner_q(0.5) - inner_q(a) + outer_q(1) - outer_q(0.5);
}
double integral_q2(double a) {
  if (a >= 1) return 0;
  if (a >= 0.5) return outer_q2(1) - outer_q2(a);
  return inner_q2(0.5) - inner_q2(a) + outer_q2(1) - outer_q2(0.5);
}

// A(u): the kernel integrated over the plane at distance |u| from the particle,
// 2 pi int_|u|^h W(r) r dr = 16 / h I(|u| / h).
double plane_integral(double u, double h) { return 16.0 / h * integral_q(std::fabs(u) / h); }

// V(u): the kernel integrated over the half-space beyond a plane at distance u (negative: the
// particle is inside the solid): int_u^h A(t) dt = 16 (J(a) - a I(a)) with a = u / h (by parts),
// and 1 - V(-u) inside.
double half_space_share(double u, double h) {
  if (u >= h) return 0;
  if (u < 0) return 1 - half_space_share(-u, h);
  const double a = u / h;
  return 16.0 * (integral_q2(a) - a * integral_q(a));
}

constexpr double kNoSlipWeightMax = 1.5;

// The friction integrals, with the pair gradient's normalisation g (grad W = g W'(r) x / r): for
// the points of the half-space beyond u (the distance from the wall's surface; negative: inside),
// int beta (-g W'(r) / r) / (r^2 + 0.01 h^2) x_a^2 dV, normal and one tangential axis. Plane by
// plane: at depth t the plane contributes 2 pi int phi(r) rho drho times t^2 (normal) or times
// rho^2 / 2 (a tangent: the mean of x^2 over the circle), r^2 = t^2 + rho^2 < h^2. A plane's
// contribution does not depend on u, so the planes are integrated once, on a fine grid over
// [-h, h], and each table entry sums those beyond its u with its weight beta.
struct FrictionPlanes {
  static constexpr int kPlanes = 4096;
  double h = 0, dt = 0;
  std::vector<double> normal, tangent;  // per plane, times its thickness dt
};

FrictionPlanes friction_planes(double h, double g) {
  FrictionPlanes p;
  p.h = h, p.dt = 2 * h / FrictionPlanes::kPlanes;
  p.normal.resize(FrictionPlanes::kPlanes), p.tangent.resize(FrictionPlanes::kPlanes);
  const double eps2 = 0.01 * h * h;
  const int rings = 200;
  for (int a = 0; a < FrictionPlanes::kPlanes; ++a) {
    const double t = -h + (a + 0.5) * p.dt;
    const double dr = std::sqrt(std::max(0.0, h * h - t * t)) / rings;
    double n = 0, tg = 0;
    for (int b = 0; b < rings; ++b) {
      const double rho = (b + 0.5) * dr, r = std::sqrt(t * t + rho * rho);
      const double phi = -g * cubic_dw_dr_d(r, h) / r / (r * r + eps2);
      n += phi * rho;
      tg += phi * rho * rho * rho / 2;
    }
    p.normal[a] = 2 * kPi * n * dr * t * t * p.dt;
    p.tangent[a] = 2 * kPi * tg * dr * p.dt;
  }
  return p;
}

void friction_integrals(const FrictionPlanes& p, double u, double& normal, double& tangent) {
  normal = tangent = 0;
  for (int a = 0; a < FrictionPlanes::kPlanes; ++a) {
    const double t = -p.h + (a + 0.5) * p.dt;
    if (t < u) continue;
    // No slip at the wall's surface (Morris, Fox & Zhu 1997): the wall point at depth t - u
    // behind it carries the fluid's velocity extrapolated through zero, -(t - u) / u v_i, so it
    // weighs 1 + (t - u) / u = t / u, at most 1.5 (their bound, for a particle at the surface).
    const double beta = u > 0 ? std::min(t / u, kNoSlipWeightMax) : kNoSlipWeightMax;
    normal += beta * p.normal[a];
    tangent += beta * p.tangent[a];
  }
}

// The table entry for u (u = the distance from the face into the fluid plus the offset), NaN-safe:
// a particle whose position went non-finite reads the first entry and the finite-state check
// then names it.
struct TableAt {
  int i;
  float f;
};
TableAt table_at(float u, float h, float du, int size) {
  float t = (u + h) / du;
  t = t > 0.0f ? t : 0.0f;
  t = std::min(t, static_cast<float>(size - 1) - 1e-3f);
  const int i = static_cast<int>(t);
  return {i, t - static_cast<float>(i)};
}

float lerp(const std::vector<float>& table, TableAt a) { return table[a.i] + a.f * (table[a.i + 1] - table[a.i]); }

}  // namespace

void WallMap::friction(float x, float y, float z, float& fx, float& fy, float& fz) const {
  const float p[3] = {x, y, z};
  float out[3] = {0, 0, 0};
  for (int w = 0; w < 6; ++w) {
    if (!enabled[w]) continue;
    const int axis = w / 2;
    const float inward = (w % 2 == 0) ? 1.0f : -1.0f;
    const float u = (p[axis] - face[w]) * inward + offset_m;
    if (u >= h) continue;
    const TableAt a = table_at(u, h, du, kTableSize);
    const float normal = lerp(friction_normal, a), tangent = lerp(friction_tangent, a);
    for (int k = 0; k < 3; ++k) out[k] += k == axis ? normal : tangent;
  }
  fx += out[0], fy += out[1], fz += out[2];
}

void WallMap::sample(float x, float y, float z, float& density_hat, float& gx, float& gy, float& gz) const {
  const float p[3] = {x, y, z};
  // Shares and gradients of the walls within reach. Where walls meet, their half-spaces overlap:
  // the share of the union is 1 - prod (1 - V_w), exact for a kernel that factorises along the
  // axes (a Gaussian; the cubic spline is close), so an edge or a corner is not counted twice.
  float share[6], grad[6];
  int axis_of[6], n = 0;
  for (int w = 0; w < 6; ++w) {
    if (!enabled[w]) continue;
    const int axis = w / 2;
    const float inward = (w % 2 == 0) ? 1.0f : -1.0f;  // the normal into the fluid
    const float u = (p[axis] - face[w]) * inward + offset_m;
    if (u >= h) continue;
    const TableAt a = table_at(u, h, du, kTableSize);
    share[n] = lerp(this->share, a);
    // The share grows toward the wall: its gradient points out of the fluid, -inward.
    grad[n] = -inward * lerp(slope, a) * gradient_scale;
    axis_of[n] = axis;
    ++n;
  }
  if (n == 0) return;
  float outside = 1;  // prod (1 - V_w)
  for (int k = 0; k < n; ++k) outside *= 1 - share[k];
  density_hat += 1 - outside;
  float g[3] = {0, 0, 0};
  for (int k = 0; k < n; ++k) {
    float others = 1;
    for (int o = 0; o < n; ++o)
      if (o != k) others *= 1 - share[o];
    g[axis_of[k]] += grad[k] * others;
  }
  gx += g[0], gy += g[1], gz += g[2];
}

WallMap make_wall_map(const float lo[3], const float hi[3], const bool low_wall[3], const bool high_wall[3],
                      const CubicKernel& kernel, double s) {
  WallMap m;
  const double h = kernel.h;
  m.h = kernel.h;
  for (int a = 0; a < 3; ++a) {
    m.enabled[2 * a] = low_wall[a], m.face[2 * a] = lo[a];
    m.enabled[2 * a + 1] = high_wall[a], m.face[2 * a + 1] = hi[a];
  }
  m.du = static_cast<float>(2 * h / (kTableSize - 1));
  m.share.resize(kTableSize);
  m.slope.resize(kTableSize);
  for (int k = 0; k < kTableSize; ++k) {
    const double u = -h + k * m.du;
    m.share[k] = static_cast<float>(half_space_share(u, h));
    m.slope[k] = static_cast<float>(plane_integral(u, h));
  }
  // A particle of the first lattice layer, half a spacing from the face: the density and the
  // (normalised) gradient sum of its fluid neighbours, all on its side of the wall.
  const int reach = static_cast<int>(std::ceil(h / s));
  double fluid_share = 0, fluid_gradient = 0, weights = 0;
  for (int i = -reach; i <= reach; ++i)
    for (int j = -reach; j <= reach; ++j)
      for (int k = -reach; k <= reach; ++k) {
        const double r = s * std::sqrt(static_cast<double>(i * i + j * j + k * k));
        const double w = cubic_w_d(r, h);
        weights += w;
        if (k < 0) continue;
        fluid_share += w;
        if (r > 0) fluid_gradient += cubic_dw_dr_d(r, h) * (-k * s) / r;  // z-component of grad W(x_i - x_j)
      }
  const double volume = 1 / weights;
  fluid_share *= volume;
  fluid_gradient *= volume * (kernel.grad_scale / (48.0 / (kPi * h * h * h) / h));
  // Offset: where the half-space share makes up the density the missing layers would have.
  double u_lo = 0, u_hi = h;
  for (int it = 0; it < 60; ++it) {
    const double mid = 0.5 * (u_lo + u_hi);
    (half_space_share(mid, h) > 1 - fluid_share ? u_lo : u_hi) = mid;
  }
  const double u0 = 0.5 * (u_lo + u_hi);
  m.offset_m = static_cast<float>(u0 - 0.5 * s);
  // Gradient: the wall's must cancel the fluid's (a positive z-sum: the neighbours lie above).
  m.gradient_scale = static_cast<float>(fluid_gradient / plane_integral(u0, h));
  // Friction, with the pair gradients' own normalisation (the lists' V_j grad W).
  const FrictionPlanes planes = friction_planes(h, kernel.grad_scale / (48.0 / (kPi * h * h * h) / h));
  m.friction_normal.resize(kTableSize);
  m.friction_tangent.resize(kTableSize);
  for (int k = 0; k < kTableSize; ++k) {
    double normal = 0, tangent = 0;
    friction_integrals(planes, -h + k * m.du, normal, tangent);
    m.friction_normal[k] = static_cast<float>(normal);
    m.friction_tangent[k] = static_cast<float>(tangent);
  }
  return m;
}

WallMap domain_wall_map(const SimulationParams& p) {
  bool low[3], high[3];
  for (int a = 0; a < 3; ++a) low[a] = p.clamp_lo[a] < p.box_lo[a], high[a] = p.clamp_hi[a] > p.box_hi[a];
  return make_wall_map(p.box_lo, p.box_hi, low, high, p.incompressible.kernel, p.particle_spacing_m);
}

SortedSolids static_solids_beside_walls(const SimulationModel& model) {
  const SortedSolids& st = model.static_solids;
  std::vector<std::uint32_t> keep;
  for (std::uint32_t k = 0; k < st.size(); ++k)
    if (st.body[k] != kWall) keep.push_back(k);
  std::vector<float> x(keep.size()), y(keep.size()), z(keep.size());
  for (std::size_t q = 0; q < keep.size(); ++q) x[q] = st.x[keep[q]], y[q] = st.y[keep[q]], z[q] = st.z[keep[q]];
  CellSort sort;
  sort.sort(model.params.grid, x.data(), y.data(), z.data(), keep.size());
  SortedSolids out;
  out.resize(keep.size());
  for (std::size_t q = 0; q < keep.size(); ++q) {
    const std::uint32_t k = keep[sort.order[q]];
    out.x[q] = st.x[k], out.y[q] = st.y[k], out.z[q] = st.z[k];
    out.vx[q] = out.vy[q] = out.vz[q] = 0;
    out.volume[q] = st.volume[k], out.viscosity[q] = st.viscosity[k];
    out.no_slip[q] = st.no_slip[k], out.pressure[q] = 0;
    out.body[q] = st.body[k], out.source[q] = st.source[k];
  }
  out.cell_start = sort.cell_start;
  return out;
}

}  // namespace hapfluid::sim
