// SPH smoothing kernels of Müller, Charypar and Gross 2003 ("Particle-based fluid simulation for
// interactive applications"), the ones the paper uses (§3.1): poly6 for density (eq. 2), the
// gradient of the spiky kernel for pressure (eq. 5) and the Laplacian of the viscosity kernel
// (eqs. 6 and 9). h is the support radius: every kernel is zero for r >= h.
//
// Pure inline functions of r (or r^2) with the normalisation constants precomputed once per
// simulation, so the CPU solver and the Vulkan shaders evaluate the very same expressions.
#pragma once

#include <cmath>

namespace hapfluid::sim {

inline constexpr double kPi = 3.14159265358979323846;

struct KernelConstants {
  float h = 0;           // support radius, m
  float h2 = 0;          // h^2
  float poly6 = 0;       // 315 / (64 pi h^9)
  float spiky_grad = 0;  // -45 / (pi h^6): dW/dr = spiky_grad * (h - r)^2
  float visc_lap = 0;    // 45 / (pi h^6): laplacian W = visc_lap * (h - r)
};

inline KernelConstants make_kernel_constants(double support_radius_m) {
  const double h = support_radius_m;
  KernelConstants k;
  k.h = static_cast<float>(h);
  k.h2 = static_cast<float>(h * h);
  k.poly6 = static_cast<float>(315.0 / (64.0 * kPi * std::pow(h, 9)));
  k.spiky_grad = static_cast<float>(-45.0 / (kPi * std::pow(h, 6)));
  k.visc_lap = static_cast<float>(45.0 / (kPi * std::pow(h, 6)));
  return k;
}

// Branch-free forms the solver's vectorised pair loops use. Outside the support they are fed
// hr = max(h - r, 0) = 0 (or r^2 >= h^2), which makes them zero.
// poly6 shape (h^2 - r^2)^3, clamped at 0; W = k.poly6 * shape (sums are scaled once).
inline float poly6_shape(const KernelConstants& k, float r2) {
  const float d = k.h2 - r2 > 0.0f ? k.h2 - r2 : 0.0f;
  return d * d * d;
}
// Spiky gradient: grad W(x) = spiky_grad_factor * x = -45 / (pi h^6) (h - r)^2 x / r, r > 0.
inline float spiky_grad_factor(const KernelConstants& k, float r, float hr) { return k.spiky_grad * hr * hr / r; }
// Viscosity kernel Laplacian 45 / (pi h^6) (h - r).
inline float viscosity_laplacian_of(const KernelConstants& k, float hr) { return k.visc_lap * hr; }

// poly6: W(r) = 315 / (64 pi h^9) (h^2 - r^2)^3, as a function of r^2 (no square root needed).
inline float poly6(const KernelConstants& k, float r2) { return k.poly6 * poly6_shape(k, r2); }

// Spiky gradient over r, zero outside the support and at r = 0 (no direction there).
inline float spiky_grad_over_r(const KernelConstants& k, float r) {
  if (r >= k.h || r <= 0.0f) return 0.0f;
  return spiky_grad_factor(k, r, k.h - r);
}

// Viscosity kernel Laplacian, zero outside the support.
inline float viscosity_laplacian(const KernelConstants& k, float r) {
  return r >= k.h ? 0.0f : viscosity_laplacian_of(k, k.h - r);
}

// The kernels in double with explicit h, for tests (normalisation, finite differences).
inline double poly6_d(double r, double h) {
  return r >= h ? 0.0 : 315.0 / (64.0 * kPi * std::pow(h, 9)) * std::pow(h * h - r * r, 3);
}
inline double spiky_d(double r, double h) {
  return r >= h ? 0.0 : 15.0 / (kPi * std::pow(h, 6)) * std::pow(h - r, 3);
}
inline double spiky_grad_d(double r, double h) {  // dW/dr
  return r >= h ? 0.0 : -45.0 / (kPi * std::pow(h, 6)) * (h - r) * (h - r);
}
inline double viscosity_d(double r, double h) {
  if (r >= h || r <= 0) return 0.0;
  return 15.0 / (2.0 * kPi * h * h * h) *
         (-r * r * r / (2 * h * h * h) + r * r / (h * h) + h / (2 * r) - 1);
}
inline double viscosity_laplacian_d(double r, double h) {
  return r >= h ? 0.0 : 45.0 / (kPi * std::pow(h, 6)) * (h - r);
}

}  // namespace hapfluid::sim
