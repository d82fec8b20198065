#include "hapfluid/sim/wall_map.hpp"

#include <algorithm>
#include <cmath>

namespace hapfluid::sim {
namespace {

constexpr int kTableSize = 513;

// A(u): the kernel integrated over the plane at distance |u| from the particle,
// 2 pi int_|u|^h W(r) r dr.
double plane_integral(double u, double h) {
  const double a = std::fabs(u);
  if (a >= h) return 0;
  const int n = 400;
  double sum = 0;
  for (int k = 0; k < n; ++k) {
    const double r = a + (h - a) * (k + 0.5) / n;
    sum += cubic_w_d(r, h) * r;
  }
  return 2 * kPi * sum * (h - a) / n;
}

// V(u): the kernel integrated over the half-space beyond a plane at distance u (negative: the
// particle is inside the solid): int_u^h A(t) dt, and 1 - V(-u) inside.
double half_space_share(double u, double h) {
  if (u >= h) return 0;
  if (u < 0) return 1 - half_space_share(-u, h);
  const int n = 400;
  double sum = 0;
  for (int k = 0; k < n; ++k) sum += plane_integral(u + (h - u) * (k + 0.5) / n, h);
  return sum * (h - u) / n;
}

}  // namespace

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
    // NaN-safe clamp: a particle whose position went non-finite must read the table's first
    // entry, not an index cast from NaN; the finite-state check then names it.
    float t = (u + h) / du;
    t = t > 0.0f ? t : 0.0f;
    t = std::min(t, static_cast<float>(kTableSize - 1) - 1e-3f);
    const int i = static_cast<int>(t);
    const float f = t - static_cast<float>(i);
    share[n] = this->share[i] + f * (this->share[i + 1] - this->share[i]);
    // The share grows toward the wall: its gradient points out of the fluid, -inward.
    grad[n] = -inward * (slope[i] + f * (slope[i + 1] - slope[i])) * gradient_scale;
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
  return m;
}

}  // namespace hapfluid::sim
