// A tank of water at rest (the "fluid pool" every scenario starts from): the walls must hold the
// fluid, the start-up motion must die out, and the pressure must be hydrostatic, p = rho0 g d.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "test_support.hpp"

using namespace hapfluid::sim;
namespace config = hapfluid::config;

namespace {

struct Profile {
  std::vector<double> depth_m, pressure_pa;  // per 2 cm band of the bulk
};

// Mean pressure and depth in 2 cm bands of the bulk (more than one support radius from the walls
// and the surface). Free surface: half a spacing above the top particle layer (the mean height
// of the top 100 particles).
Profile pressure_profile(const CpuSolver& solver, const config::Scene& scene) {
  const auto& f = solver.model().fluid;
  const float* lo = solver.params().box_lo;
  const float* hi = solver.params().box_hi;
  std::vector<float> z(f.z.begin(), f.z.end());
  std::sort(z.begin(), z.end());
  double top = 0;
  for (std::size_t i = z.size() - 100; i < z.size(); ++i) top += z[i] / 100.0;
  const double surface = top + 0.5 * scene.fluid.particle_spacing_m;
  const double h = scene.support_radius();
  Profile out;
  for (double zc = 0.03; zc < 0.15; zc += 0.02) {
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
    out.depth_m.push_back(n > 0 ? depth / n : 0);
    out.pressure_pa.push_back(n > 0 ? p / n : 0);
  }
  return out;
}

// Mean first moment of the pressure gradient over the bulk, tr(M_i)/3 with
// M_i = -sum_j V_j grad W_ij (x) r_ij over fluid and wall neighbours (1 for an exact gradient
// of a linear field): with the plain volumes V = m / rho and with the corrected volumes of the
// pressure force (V * volume_correction, gradient_correction.hpp; walls keep theirs).
struct FirstMoment {
  double plain = 0, corrected = 0;
};
FirstMoment bulk_first_moment(const CpuSolver& solver, double surface) {
  const auto& f = solver.model().fluid;
  const auto& st = solver.model().static_solids;
  const KernelConstants& k = solver.params().kernel;
  const float* lo = solver.params().box_lo;
  const float* hi = solver.params().box_hi;
  const double h = k.h;
  FirstMoment sum;
  int n = 0;
  for (std::size_t i = 0; i < f.size(); ++i) {
    if (f.x[i] < lo[0] + h || f.x[i] > hi[0] - h || f.y[i] < lo[1] + h || f.y[i] > hi[1] - h || f.z[i] > surface - h)
      continue;
    double plain = 0, corrected = 0;
    auto add = [&](double dx, double dy, double dz, double volume, double correction) {
      const double r = std::sqrt(dx * dx + dy * dy + dz * dz);
      if (r >= h || r <= 0) return;
      const double moment = -spiky_grad_over_r(k, static_cast<float>(r)) * r * r / 3;  // -(r . grad W) / 3
      plain += volume * moment;
      corrected += volume * correction * moment;
    };
    for (std::size_t j = 0; j < f.size(); ++j)
      add(f.x[i] - f.x[j], f.y[i] - f.y[j], f.z[i] - f.z[j], f.volume[j], f.volume_correction[j]);
    for (std::size_t j = 0; j < st.size(); ++j) add(f.x[i] - st.x[j], f.y[i] - st.y[j], f.z[i] - st.z[j], st.volume[j], 1.0);
    sum.plain += plain;
    sum.corrected += corrected;
    ++n;
  }
  return {sum.plain / n, sum.corrected / n};
}

}  // namespace

TEST(Hydrostatic, TankSettlesToHydrostaticPressureWithoutLeaking) {
  const auto scene = config::load_scene("tests/sim_gpu/scenes/hydrostatic_tank.toml");
  CpuSolver solver(build_model(scene), 2);
  const auto& f = solver.model().fluid;
  const std::size_t count = f.size();
  const double mass_before = count * solver.params().fluid_particle_mass_kg;

  test::run_for(solver, 0.1, 0.02);
  const double ke_start = test::fluid_kinetic_energy(solver);
  test::run_for(solver, 1.1, 0.02);
  // Time-averaged profile over the last 0.3 s (10 snapshots): the settled column still jitters.
  const int snapshots = 10;
  Profile mean;
  double worst_snapshot_band = 0;
  for (int k = 0; k < snapshots; ++k) {
    test::run_for(solver, 0.03, 0.03);
    const Profile now = pressure_profile(solver, scene);
    // The 10% holds for every settled snapshot, not only on average.
    for (std::size_t b = 0; b < now.depth_m.size(); ++b) {
      const double expected = scene.fluid.rest_density_kg_m3 * 9.81 * now.depth_m[b];  // Pa
      EXPECT_NEAR(now.pressure_pa[b], expected, 0.10 * expected) << "snapshot " << k << ", depth " << now.depth_m[b] << " m";
      worst_snapshot_band = std::max(worst_snapshot_band, std::abs(now.pressure_pa[b] / expected - 1));
    }
    if (mean.depth_m.empty()) mean.depth_m.assign(now.depth_m.size(), 0), mean.pressure_pa.assign(now.depth_m.size(), 0);
    for (std::size_t b = 0; b < now.depth_m.size(); ++b) {
      mean.depth_m[b] += now.depth_m[b] / snapshots;
      mean.pressure_pa[b] += now.pressure_pa[b] / snapshots;
    }
  }
  const double ke_late = test::fluid_kinetic_energy(solver);

  // The pressure gradient is exact to first order in the settled (disordered) bulk: the first
  // moment of the kernel gradient over the pressure force's volumes is the identity. With the
  // plain volumes m / rho it falls ~4% short (the poly6 density over-counts the relaxed packing),
  // which made the column's pressure gradient ~8% steep (gradient_correction.hpp).
  {
    std::vector<float> z(f.z.begin(), f.z.end());
    std::sort(z.begin(), z.end());
    const FirstMoment m = bulk_first_moment(solver, z[z.size() - 50]);
    std::cout << "hydrostatic: bulk first moment tr(M)/3 " << m.plain << " with V = m / rho, " << m.corrected
              << " with the corrected volumes\n";
    EXPECT_NEAR(m.corrected, 1.0, 0.01);
  }

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

  const double g = 9.81, rho0 = scene.fluid.rest_density_kg_m3;
  const std::size_t bands = mean.depth_m.size();
  ASSERT_GE(bands, 5u);
  double worst = 0;
  for (std::size_t b = 0; b < bands; ++b) {
    const double expected = rho0 * g * mean.depth_m[b];  // Pa
    // Within 10% of rho0 g d pointwise in the bulk. The top-layer convention for the
    // surface is itself uncertain by a fraction of a spacing (a few % at the shallowest band).
    // Without the first-moment correction of the pressure force the relaxed bulk read 7-12% high.
    EXPECT_NEAR(mean.pressure_pa[b], expected, 0.10 * expected) << "depth " << mean.depth_m[b] << " m";
    worst = std::max(worst, std::abs(mean.pressure_pa[b] / expected - 1));
  }
  std::cout << "hydrostatic: worst bulk band " << 100 * worst << " % from rho0 g d (time-averaged), "
            << 100 * worst_snapshot_band << " % in a single snapshot\n";
  // The hydrostatic law itself, dp/dd = rho0 g (least squares over the bands).
  double md = 0, mp = 0;
  for (std::size_t b = 0; b < bands; ++b) md += mean.depth_m[b] / bands, mp += mean.pressure_pa[b] / bands;
  double sdd = 0, sdp = 0;
  for (std::size_t b = 0; b < bands; ++b) {
    sdd += (mean.depth_m[b] - md) * (mean.depth_m[b] - md);
    sdp += (mean.depth_m[b] - md) * (mean.pressure_pa[b] - mp);
  }
  const double gradient = sdp / sdd;  // Pa/m
  std::cout << "hydrostatic: dp/dd = " << gradient << " Pa/m (rho0 g = " << rho0 * g << ")\n";
  // Within 5%: without the first-moment correction of the pressure force it is not.
  EXPECT_NEAR(gradient, rho0 * g, 0.05 * rho0 * g);
}

// Water at rest on the default solver (config/scenes/hydrostatic_tank.toml: DFSPH, 0.001 Pa s,
// 5 ms steps, settled from its start lattice): the volume-mapped walls alone hold it (no clamp
// event, no particle lost), and it stays at its rest density. The density solve stops
// once the mean compression it predicts for the step is below fluid.density_error_percent
// (0.1 %), so the mean density error over the run is below that too; single particles stray
// further (1-1.5 % above rest in the settled packing). Not held yet: its particles keep moving
// at ~0.04 m/s rms, where 0.01 m/s is the target (sim_gpu/README.md).
TEST(Hydrostatic, DfsphWaterStaysInItsTankAtRestDensity) {
  const auto scene = config::load_scene("config/scenes/hydrostatic_tank.toml");
  const auto solver_ptr = make_cpu_solver(build_model(scene), 2);
  Solver& solver = *solver_ptr;
  ASSERT_STREQ(solver.method(), "dfsph");
  ASSERT_LE(scene.fluid.viscosity_pa_s, 0.001);
  const auto& f = solver.model().fluid;
  const std::size_t count = f.size();
  const double rho0 = scene.fluid.rest_density_kg_m3;
  const int snapshots = static_cast<int>(std::lround(scene.duration_s / 0.1));
  double mean_error = 0;
  for (int k = 0; k < snapshots; ++k) {
    test::run_for(solver, 0.1, 0.1);
    solver.sync_and_check_finite();
    double sum = 0;
    for (float rho : f.density) sum += rho / rho0 - 1;
    mean_error += sum / static_cast<double>(f.size()) / snapshots;
  }
  std::cout << "dfsph tank at rest: mean density error " << 100 * mean_error << " % over " << scene.duration_s
            << " s, " << solver.steps() << " steps, clamp events " << solver.clamped_particle_count() << "\n";
  EXPECT_LT(mean_error, scene.fluid.density_error_percent / 100);
  EXPECT_GT(mean_error, -scene.fluid.density_error_percent / 100);
  // A particle that reaches the last-resort clamp planes (within the walls' reach) is put back
  // and counted: none did.
  EXPECT_EQ(solver.clamped_particle_count(), 0u);
  EXPECT_EQ(f.size(), count);
}
