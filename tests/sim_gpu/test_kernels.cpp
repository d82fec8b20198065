// The SPH kernels of Müller et al. 2003 (paper §3.1): each must integrate to one over its
// support (otherwise densities are off by that factor), and the closed forms the solver uses for
// the spiky gradient and the viscosity Laplacian must be the derivatives of the kernels.
#include <gtest/gtest.h>

#include <cmath>

#include "hapfluid/sim/kernels.hpp"

using namespace hapfluid::sim;

namespace {

// Integral over 3D space of a radial function: 4 pi int_0^h r^2 f(r) dr (midpoint rule).
template <class F>
double radial_integral(F f, double h) {
  const int n = 200000;
  double sum = 0;
  for (int i = 0; i < n; ++i) {
    const double r = (i + 0.5) * h / n;
    sum += 4 * kPi * r * r * f(r) * (h / n);
  }
  return sum;
}

}  // namespace

TEST(Kernels, Poly6SpikyAndViscosityIntegrateToOne) {
  for (double h : {0.01, 0.02, 0.1}) {
    EXPECT_NEAR(radial_integral([&](double r) { return poly6_d(r, h); }, h), 1.0, 1e-6) << "h = " << h;
    EXPECT_NEAR(radial_integral([&](double r) { return spiky_d(r, h); }, h), 1.0, 1e-6) << "h = " << h;
    EXPECT_NEAR(radial_integral([&](double r) { return viscosity_d(r, h); }, h), 1.0, 1e-4) << "h = " << h;
  }
}

TEST(Kernels, FloatPoly6MatchesDoubleAndVanishesOutsideSupport) {
  const double h = 0.02;
  const KernelConstants k = make_kernel_constants(h);
  for (double r : {0.0, 0.003, 0.01, 0.019}) {
    EXPECT_NEAR(poly6(k, static_cast<float>(r * r)), poly6_d(r, h), 1e-5 * poly6_d(0, h)) << "r = " << r;
  }
  EXPECT_EQ(poly6(k, static_cast<float>(h * h)), 0.0f);
  EXPECT_EQ(spiky_grad_over_r(k, static_cast<float>(h)), 0.0f);
  EXPECT_EQ(viscosity_laplacian(k, static_cast<float>(1.5 * h)), 0.0f);
}

TEST(Kernels, SpikyGradientIsTheDerivativeOfSpiky) {
  const double h = 0.02, e = 1e-7;
  const KernelConstants k = make_kernel_constants(h);
  for (double r : {0.002, 0.007, 0.012, 0.018}) {
    const double fd = (spiky_d(r + e, h) - spiky_d(r - e, h)) / (2 * e);
    EXPECT_NEAR(spiky_grad_d(r, h), fd, 1e-6 * std::abs(fd)) << "r = " << r;
    // The solver's form: grad W = spiky_grad_over_r * x, so its magnitude is dW/dr.
    EXPECT_NEAR(spiky_grad_over_r(k, static_cast<float>(r)) * r, fd, 1e-4 * std::abs(fd)) << "r = " << r;
  }
}

TEST(Kernels, ViscosityLaplacianMatchesFiniteDifferences) {
  // Laplacian of a radial function: W'' + 2 W' / r.
  const double h = 0.02, e = 1e-6;
  const KernelConstants k = make_kernel_constants(h);
  for (double r : {0.004, 0.008, 0.012, 0.016}) {
    const double w0 = viscosity_d(r, h), wp = viscosity_d(r + e, h), wm = viscosity_d(r - e, h);
    const double lap = (wp - 2 * w0 + wm) / (e * e) + 2 / r * (wp - wm) / (2 * e);
    EXPECT_NEAR(viscosity_laplacian_d(r, h), lap, 1e-3 * std::abs(lap)) << "r = " << r;
    EXPECT_NEAR(viscosity_laplacian(k, static_cast<float>(r)), lap, 1e-3 * std::abs(lap)) << "r = " << r;
  }
}
