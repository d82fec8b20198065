// The cubic spline kernel (Monaghan 1992) of the incompressible solver, with support radius h
// (zero for r >= h). Density and pressure gradient use the same kernel, as the DFSPH factor
// requires: the factor predicts how a density responds to the velocity change its own gradient
// causes. Pure inline functions so that the vectorised pair loops evaluate them branch-free.
#pragma once

#include <cmath>

#include "hapfluid/sim/kernels.hpp"

namespace hapfluid::sim {

struct CubicKernel {
  float h = 0, h2 = 0, inv_h = 0;
  float w_scale = 0;     // 8 / (pi h^3)
  // dW/dr = grad_scale * g(q) with g(q) = q (3q - 2) for q <= 1/2, -(1 - q)^2 up to 1; grad_scale
  // is 6 w_scale / h, times 1 / (the gradient's first moment on the rest lattice) so that a
  // linear pressure field has the exact gradient there (1.020 at h = 2 spacings: without it a
  // column at rest would carry 2 % less than rho0 g depth).
  float grad_scale = 0;
};

inline CubicKernel make_cubic_kernel(double h, double gradient_moment = 1.0) {
  CubicKernel k;
  k.h = static_cast<float>(h);
  k.h2 = static_cast<float>(h * h);
  k.inv_h = static_cast<float>(1.0 / h);
  k.w_scale = static_cast<float>(8.0 / (kPi * h * h * h));
  k.grad_scale = static_cast<float>(6.0 * 8.0 / (kPi * h * h * h) / h / gradient_moment);
  return k;
}

// W(r); r >= 0.
inline float cubic_w(const CubicKernel& k, float r) {
  const float q = r * k.inv_h;
  const float a = 1.0f - q > 0.0f ? 1.0f - q : 0.0f;
  const float inner = 6.0f * q * q * (q - 1.0f) + 1.0f;
  return k.w_scale * (q <= 0.5f ? inner : 2.0f * a * a * a);
}

// (dW/dr) / r, so that grad W(x_i - x_j) = cubic_grad_over_r * (x_i - x_j); finite at r = 0
// (where the gradient itself is zero).
inline float cubic_grad_over_r(const CubicKernel& k, float r) {
  const float q = r * k.inv_h;
  const float a = 1.0f - q > 0.0f ? 1.0f - q : 0.0f;
  // q <= 1/2: q (3q - 2) / r = (3q - 2) / h; beyond: -(1 - q)^2 / r. The divisor is a select (r
  // = 0 takes the inner piece) so that the whole function if-converts and vectorises.
  const float inner = (3.0f * q - 2.0f) * k.inv_h;
  const float outer = -a * a / (r > 0.0f ? r : 1.0f);
  return k.grad_scale * (q <= 0.5f ? inner : outer);
}

// The same in double with explicit h, for tests and set-up sums.
inline double cubic_w_d(double r, double h) {
  const double q = r / h;
  if (q >= 1) return 0;
  const double s = 8.0 / (kPi * h * h * h);
  return q <= 0.5 ? s * (6 * q * q * q - 6 * q * q + 1) : s * 2 * (1 - q) * (1 - q) * (1 - q);
}
inline double cubic_dw_dr_d(double r, double h) {
  const double q = r / h;
  if (q >= 1) return 0;
  const double l = 48.0 / (kPi * h * h * h) / h;
  return q <= 0.5 ? l * q * (3 * q - 2) : -l * (1 - q) * (1 - q);
}

}  // namespace hapfluid::sim
