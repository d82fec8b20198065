// A tank of water at rest (the "fluid pool" every scenario starts from): the walls must hold the
// fluid, the start-up motion must die out, and the pressure must be hydrostatic, p = rho0 g d.
#include <gtest/gtest.h>

#include <cmath>

#include "test_support.hpp"

using namespace hapfluid::sim;
namespace config = hapfluid::config;

TEST(Hydrostatic, TankSettlesToHydrostaticPressureWithoutLeaking) {
  const auto scene = config::load_scene("tests/sim_gpu/scenes/hydrostatic_tank.toml");
  CpuSolver solver(build_model(scene), 2);
  const auto& f = solver.model().fluid;
  const std::size_t count = f.size();
  const double mass_before = count * solver.params().fluid_particle_mass_kg;

  test::run_for(solver, 0.1, 0.02);
  const double ke_start = test::fluid_kinetic_energy(solver);
  test::run_for(solver, 1.4, 0.02);
  const double ke_late = test::fluid_kinetic_energy(solver);

  // Kinetic energy decays: the start-up motion (the column settling onto the floor) is damped
  // to a residual jitter of a few mm/s (J; 2 kg of water at 1 cm/s is 1e-4 J).
  EXPECT_LT(ke_late, 0.2 * ke_start) << "start " << ke_start << " J, late " << ke_late << " J";
  EXPECT_LT(ke_late, 2e-4) << "the column is not at rest";
  // Fluid mass is exact (particles are never created or destroyed) and nothing left the tank:
  // no particle reached a wall's particle layer, where the last-resort clamp would act.
  EXPECT_EQ(f.size(), count);
  EXPECT_DOUBLE_EQ(f.size() * solver.params().fluid_particle_mass_kg, mass_before);
  EXPECT_EQ(solver.clamped_particle_count(), 0u);
  const float* lo = solver.params().box_lo;
  const float* hi = solver.params().box_hi;
  const float half = 0.5f * solver.params().particle_spacing_m;
  for (std::size_t i = 0; i < f.size(); ++i) {
    ASSERT_GT(f.x[i], lo[0] - half);
    ASSERT_LT(f.x[i], hi[0] + half);
    ASSERT_GT(f.y[i], lo[1] - half);
    ASSERT_LT(f.y[i], hi[1] + half);
    ASSERT_GT(f.z[i], lo[2] - half);
  }

  // Free surface: half a spacing above the top particle layer (mean of the top 100 particles).
  std::vector<float> z(f.z.begin(), f.z.end());
  std::sort(z.begin(), z.end());
  double top = 0;
  for (std::size_t i = z.size() - 100; i < z.size(); ++i) top += z[i] / 100.0;
  const double surface = top + 0.5 * scene.fluid.particle_spacing_m;
  // Bulk: more than one support radius from the walls and the surface, in 2 cm depth bands.
  const double h = scene.support_radius(), g = 9.81, rho0 = scene.fluid.rest_density_kg_m3;
  int bands = 0;
  std::vector<double> band_depth, band_pressure;
  for (double zc = 0.03; zc < surface - h - 0.01; zc += 0.02) {
    double p = 0, depth = 0;
    int n = 0;
    for (std::size_t i = 0; i < f.size(); ++i) {
      if (std::abs(f.z[i] - zc) > 0.01 || f.x[i] < lo[0] + h || f.x[i] > hi[0] - h || f.y[i] < lo[1] + h ||
          f.y[i] > hi[1] - h)
        continue;
      p += f.pressure[i];
      depth += surface - f.z[i];
      ++n;
    }
    ASSERT_GT(n, 5);
    p /= n, depth /= n;
    const double expected = rho0 * g * depth;  // Pa
    // Within 15% pointwise: the top-layer convention for the surface is itself uncertain by a
    // fraction of a spacing, and the spiky gradient on the relaxed (non-lattice) particle
    // arrangement reads a few % steep (measured 7-12% above rho0 g d).
    EXPECT_NEAR(p, expected, 0.15 * expected) << "depth " << depth << " m";
    band_depth.push_back(depth);
    band_pressure.push_back(p);
    ++bands;
  }
  EXPECT_GE(bands, 5);
  // The hydrostatic law itself, dp/dd = rho0 g, within 10% (least squares over the bands).
  double md = 0, mp = 0;
  for (int b = 0; b < bands; ++b) md += band_depth[b] / bands, mp += band_pressure[b] / bands;
  double sdd = 0, sdp = 0;
  for (int b = 0; b < bands; ++b) {
    sdd += (band_depth[b] - md) * (band_depth[b] - md);
    sdp += (band_depth[b] - md) * (band_pressure[b] - mp);
  }
  const double gradient = sdp / sdd;  // Pa/m
  std::cout << "hydrostatic: dp/dd = " << gradient << " Pa/m (rho0 g = " << rho0 * g << ")\n";
  EXPECT_NEAR(gradient, rho0 * g, 0.10 * rho0 * g);
}
