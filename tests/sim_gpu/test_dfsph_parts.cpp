// Parts of the incompressible solver that hold independently of its time stepping: the cubic
// spline kernel, the particle mass and gradient normalisation on the rest lattice, the domain
// walls' volume map, and the scene key that selects the method.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>

#include "hapfluid/config/scene.hpp"
#include "hapfluid/sim/cubic_kernel.hpp"
#include "hapfluid/sim/model.hpp"
#include "hapfluid/sim/solver.hpp"
#include "hapfluid/sim/wall_map.hpp"
#include "test_support.hpp"

using namespace hapfluid::sim;

using hapfluid::sim::test::radial_integral;

// A kernel that does not integrate to one scales every density by that factor.
TEST(CubicKernel, IntegratesToOneOverItsSupport) {
  for (double h : {0.01, 0.02, 0.1})
    EXPECT_NEAR(radial_integral([&](double r) { return cubic_w_d(r, h); }, h), 1.0, 1e-6) << "h = " << h;
}

// The pressure solve predicts densities with the gradient of the density kernel: the closed form
// must be its derivative (here without the lattice normalisation), in float as the solver uses it.
TEST(CubicKernel, GradientIsTheDerivativeOfTheKernel) {
  const double h = 0.02;
  const CubicKernel k = make_cubic_kernel(h);
  for (double q : {0.05, 0.2, 0.45, 0.5, 0.55, 0.8, 0.95}) {
    const double r = q * h, e = 1e-7;
    const double numeric = (cubic_w_d(r + e, h) - cubic_w_d(r - e, h)) / (2 * e);
    EXPECT_NEAR(cubic_dw_dr_d(r, h), numeric, 1e-6 * std::fabs(numeric) + 1e-3) << "q = " << q;
    EXPECT_NEAR(cubic_grad_over_r(k, static_cast<float>(r)) * r, numeric, 1e-4 * std::fabs(numeric)) << "q = " << q;
    EXPECT_NEAR(cubic_w(k, static_cast<float>(r)), cubic_w_d(r, h), 1e-5 * cubic_w_d(0, h)) << "q = " << q;
  }
  EXPECT_EQ(cubic_w(k, static_cast<float>(h)), 0.0f);
  EXPECT_EQ(cubic_grad_over_r(k, static_cast<float>(1.01 * h)), 0.0f);
}

// The particle mass makes the rest lattice exactly rho0 (the solver's target density), and the
// normalised gradient turns a linear pressure field on it into its exact gradient, so that a
// column at rest carries rho0 g depth.
TEST(CubicKernel, RestLatticeHasRestDensityAndAnExactGradient) {
  const double s = 0.01, h = 0.02, rho0 = 1000;
  const double mass = cubic_lattice_particle_mass(rho0, s, h);
  const double moment = cubic_lattice_gradient_moment(s, h);
  EXPECT_NEAR(moment, 1.020, 0.001);  // the raw cubic spline's first moment at h = 2 spacings
  const CubicKernel k = make_cubic_kernel(h, moment);
  double density = 0, first_moment = 0;
  for (int i = -2; i <= 2; ++i)
    for (int j = -2; j <= 2; ++j)
      for (int l = -2; l <= 2; ++l) {
        const double r = s * std::sqrt(double(i * i + j * j + l * l));
        density += mass * cubic_w_d(r, h);
        // sum_j V_j (z_j - z_i) dW/dz_i with the solver's float gradient.
        first_moment -= (mass / rho0) * (l * s) * cubic_grad_over_r(k, static_cast<float>(r)) * (l * s);
      }
  EXPECT_NEAR(density, rho0, 1e-9 * rho0);
  EXPECT_NEAR(first_moment, 1.0, 1e-4);
}

// Calibration of the walls' volume map: a particle of the first lattice layer, half a spacing
// from the floor, has exactly the rest density with the floor's share, and the floor's gradient
// cancels the sum of its fluid pair gradients, as a complete neighbourhood's does in the bulk.
TEST(WallMap, FirstLatticeLayerAtAFloorIsAtRest) {
  const double s = 0.01, h = 0.02;
  const CubicKernel k = make_cubic_kernel(h, cubic_lattice_gradient_moment(s, h));
  const float lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
  const bool low[3] = {false, false, true}, high[3] = {false, false, false};
  const WallMap walls = make_wall_map(lo, hi, low, high, k, s);
  const double volume = cubic_lattice_particle_mass(1.0, s, h);  // 1 / sum W on the lattice
  const float xi = 0.5f, yi = 0.5f, zi = static_cast<float>(0.5 * s);
  double fluid = 0, gz = 0;
  for (int i = -2; i <= 2; ++i)
    for (int j = -2; j <= 2; ++j)
      for (int l = 0; l <= 2; ++l) {
        const float dx = static_cast<float>(-i * s), dy = static_cast<float>(-j * s), dz = static_cast<float>(-l * s);
        const float r = std::sqrt(dx * dx + dy * dy + dz * dz);
        fluid += volume * cubic_w(k, r);
        gz += volume * cubic_grad_over_r(k, r) * dz;
      }
  float share = 0, wx = 0, wy = 0, wz = 0;
  walls.sample(xi, yi, zi, share, wx, wy, wz);
  EXPECT_NEAR(fluid + share, 1.0, 1e-3);
  EXPECT_GT(gz, 0);  // the fluid neighbours lie above
  EXPECT_NEAR(gz + wz, 0.0, 2e-3 * gz);
  EXPECT_EQ(wx, 0.0f);
  EXPECT_EQ(wy, 0.0f);
  // Beyond the support no share at all; pressed into the wall, more of it.
  float far = 0, g0 = 0, g1 = 0, g2 = 0;
  walls.sample(xi, yi, static_cast<float>(h + s), far, g0, g1, g2);
  EXPECT_EQ(far, 0.0f);
  float inside = 0;
  walls.sample(xi, yi, -static_cast<float>(0.5 * s), inside, g0, g1, g2);
  EXPECT_GT(inside, 0.5f);
  EXPECT_LT(g2, 0.0f);  // the gradient points into the wall
}

// A particle whose state went non-finite (a solve that diverged) must not make the map read
// outside its tables: the step survives to the finite-state check, which names the particle.
TEST(WallMap, ANonFinitePositionReadsNoEntryOutsideTheTables) {
  const double s = 0.01, h = 0.02;
  const CubicKernel k = make_cubic_kernel(h, cubic_lattice_gradient_moment(s, h));
  const float lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
  const bool all[3] = {true, true, true};
  const WallMap walls = make_wall_map(lo, hi, all, all, k, s);
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  for (float bad : {nan, inf, -inf}) {
    float share = 0, gx = 0, gy = 0, gz = 0;
    walls.sample(bad, 0.5f * static_cast<float>(s), bad, share, gx, gy, gz);
    EXPECT_GE(share, 0.0f) << bad;  // NaN compares false: a finite, in-range share
    EXPECT_LE(share, 1.0f) << bad;
  }
}

// fluid.solver picks the method a CPU run steps with.
TEST(SolverChoice, TheSceneKeyPicksTheMethod) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "hapfluid_solver_choice";
  std::filesystem::create_directories(dir);
  for (const char* method : {"wcsph", "dfsph"}) {
    const std::filesystem::path file = dir / (std::string(method) + ".toml");
    std::ofstream(file) << "[domain]\nmin_m = [0, 0, 0]\nmax_m = [0.1, 0.1, 0.1]\n[fluid]\nsolver = \"" << method
                        << "\"\nparticle_spacing_m = 0.01\nspeed_of_sound_m_s = 10.0\n[[fluid.blocks]]\n"
                        << "min_m = [0, 0, 0]\nmax_m = [0.1, 0.1, 0.05]\n";
    const auto solver = make_cpu_solver(build_model(hapfluid::config::load_scene(file)), 1);
    EXPECT_STREQ(solver->method(), method);
    solver->step(solver->stable_time_step());
    EXPECT_EQ(solver->steps(), 1u);
  }
  std::filesystem::remove_all(dir);
}

// The contact passes search other bodies' particles only for bodies within a support radius of
// one: two bodies 2 h apart are alone, 0.9 h apart near each other, and a body whose position
// is not finite counts as near (the search stays on rather than missing a contact).
TEST(BodyReach, BodiesWithinTheSupportRadiusOfAnotherAreNear) {
  const float h = 0.02f;
  BodyParticles bp;
  bp.resize(4);
  const float x[4] = {0.0f, 0.01f, 0.01f + 2 * h, 0.03f + 2 * h};
  for (int i = 0; i < 4; ++i) bp.x[i] = x[i], bp.y[i] = 0, bp.z[i] = 0, bp.body[i] = i < 2 ? 0 : 1;
  detail::BodyReach reach;
  reach.resize(3);  // body 2 has no particles
  reach.update(bp, h);
  EXPECT_FALSE(reach.near_other(0));
  EXPECT_FALSE(reach.near_other(1));
  EXPECT_FALSE(reach.near_other(2));
  bp.x[2] = 0.01f + 0.9f * h;
  reach.update(bp, h);
  EXPECT_TRUE(reach.near_other(0));
  EXPECT_TRUE(reach.near_other(1));
  EXPECT_FALSE(reach.near_other(2));
  bp.x[2] = 0.01f + 2 * h;
  bp.y[3] = std::nanf("");
  reach.update(bp, h);
  EXPECT_TRUE(reach.near_other(1));
}
