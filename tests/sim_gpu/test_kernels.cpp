// The SPH kernels of Müller et al. 2003 (paper §3.1): each must integrate to one over its
// support (otherwise densities are off by that factor), and the closed forms the solver uses for
// the spiky gradient and the viscosity Laplacian must be the derivatives of the kernels.
#include <gtest/gtest.h>

#include <cmath>

#include "hapfluid/sim/gradient_correction.hpp"
#include "hapfluid/sim/kernels.hpp"
#include "hapfluid/sim/model.hpp"
#include "test_support.hpp"

using namespace hapfluid::sim;

using hapfluid::sim::test::radial_integral;

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

TEST(GradientCorrection, FirstMomentKernelIntegratesToOne) {
  // Wm(r) = -r W'(r) / 3 of the spiky kernel is what tr(M)/3 sums (gradient_correction.hpp);
  // it is a number-density estimate only if it integrates to one like W.
  for (double h : {0.01, 0.02, 0.1})
    EXPECT_NEAR(radial_integral([&](double r) { return -r * spiky_grad_d(r, h) / 3; }, h), 1.0, 1e-6) << "h = " << h;
}

TEST(GradientCorrection, GivesTheLatticeCellVolumeOnTheRestLatticeAndIsClampedAtAFreeSurface) {
  // On the rest lattice the particle mass makes eq. 2 read rho0, so V = m / rho0; but the poly6
  // sum's self term makes that 1% less than the cell a particle fills, s^3. The corrected volume
  // V / c of the pressure force must be exactly s^3 (the spiky gradient is scaled to an exact
  // first moment with s^3, scene_setup.cpp). Half a lattice (a free surface through the
  // particle) would read c ~ 0.5; the clamp keeps such particles from being pushed 2x harder.
  const double s = 0.01, h = 2 * s, rho0 = 1000;
  KernelConstants k = make_kernel_constants(h);
  k.spiky_grad = static_cast<float>(k.spiky_grad / lattice_gradient_moment(s, h));
  const float volume = static_cast<float>(lattice_particle_mass(rho0, s, h) / rho0);
  EXPECT_NEAR(volume, s * s * s, 0.011 * s * s * s);  // m^3: 0.99 s^3 at h = 2 spacings
  float full = 0, lower_half = 0;
  for (int i = -2; i <= 2; ++i)
    for (int j = -2; j <= 2; ++j)
      for (int l = -2; l <= 2; ++l) {
        const float r = static_cast<float>(s * std::sqrt(double(i * i + j * j + l * l)));
        if (r >= k.h) continue;
        full += moment_shape(r, k.h - r);
        if (l <= 0) lower_half += moment_shape(r, k.h - r);
      }
  EXPECT_NEAR(volume / gradient_correction(k, volume, full, 0.0f), s * s * s, 1e-5 * s * s * s);
  // The same lattice seen half as fluid and half as wall particles of the same volume.
  const float c = gradient_correction(k, volume, full, 0.0f);
  EXPECT_FLOAT_EQ(gradient_correction(k, volume, lower_half, volume * (full - lower_half)), c);
  EXPECT_EQ(gradient_correction(k, volume, lower_half, 0.0f), kGradientCorrectionMin);
  EXPECT_EQ(gradient_correction(k, volume, 3 * full, 0.0f), kGradientCorrectionMax);
}
