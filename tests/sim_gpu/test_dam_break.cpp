// Dam break against the measurements of Martin & Moyce (1952) (../shared/data): surge front
// and residual column height, the standard checks that an SPH code moves a free-surface flow at
// the right speed.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <vector>

#include "test_support.hpp"

using namespace hapfluid::sim;
namespace config = hapfluid::config;

namespace {

std::vector<std::pair<double, double>> read_table(const std::string& file) {
  std::ifstream in(file);
  std::vector<std::pair<double, double>> rows;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#' || line[0] == 'T') continue;
    std::istringstream s(line);
    double t, z;
    char comma;
    if (s >> t >> comma >> z) rows.push_back({t, z});
  }
  return rows;
}

// Surge front: the third-farthest fluid particle plus half a spacing (one or two droplets
// thrown ahead do not count as the front).
double front_x(const Solver& s) {
  std::vector<float> x(s.model().fluid.x);
  std::sort(x.begin(), x.end());
  return x[x.size() - 3] + 0.5 * s.params().particle_spacing_m;
}

// Residual column height at the wall the column started from (x = 0): the fluid mass within
// 4 spacings of the wall as a height of water at rest density over that strip. The top of the
// collapsing column breaks into a loose spray of particles at half the rest density (pressure is
// clamped at zero, nothing holds a free surface together), so its highest particles stand up to
// twice as high as the water beneath them.
double column_height(const Solver& s) {
  const double strip = 4 * s.params().particle_spacing_m;
  const double width = s.params().box_hi[1] - s.params().box_lo[1];
  std::size_t n = 0;
  for (float x : s.model().fluid.x) n += x < s.params().box_lo[0] + strip ? 1 : 0;
  return n * s.params().fluid_particle_mass_kg / (s.params().rest_density_kg_m3 * strip * width);
}

// The comparison, for either method. `incompressible`: DFSPH at water's viscosity, whose
// column keeps within 10% of the measurement for as long as the front is followed: its density
// stays within 0.1% of rest, so the column drains at the rate the flow carries water away.
void check_dam_break(const char* scene_file, bool incompressible) {
  const auto front = read_table("../shared/data/martin_moyce_1952_n2_2_front.csv");
  const auto column = read_table("../shared/data/martin_moyce_1952_n2_2_height.csv");
  ASSERT_GE(front.size(), 10u) << "reference data missing";
  ASSERT_GE(column.size(), 10u) << "reference data missing";
  const auto scene = config::load_scene(scene_file);
  const auto solver_ptr = make_cpu_solver(build_model(scene), 2);
  Solver& solver = *solver_ptr;
  ASSERT_STREQ(solver.method(), incompressible ? "dfsph" : "wcsph");
  const std::size_t count = solver.model().fluid.size();
  const double a = 0.1, g = 9.81;
  // One run, visiting the measurement times of both tables in order: front Z = x / a at
  // T = t sqrt(2 g / a); column eta = H / (2 a) at tau = t sqrt(g / a).
  struct Sample {
    double t_s, reference;
    bool is_front;
  };
  std::vector<Sample> samples;
  // T < 0.5: the gate-removal transient of the experiment.
  for (const auto& [T, Z] : front)
    if (T >= 0.5) samples.push_back({T / std::sqrt(2 * g / a), Z, true});
  // Up to tau = 2.45 (t = 0.25 s, as long as the front is followed): later the column is a
  // few spacings of water.
  for (const auto& [tau, eta] : column)
    if (tau <= 2.45) samples.push_back({tau / std::sqrt(g / a), eta, false});
  std::sort(samples.begin(), samples.end(), [](const Sample& x, const Sample& y) { return x.t_s < y.t_s; });
  int fronts = 0, columns = 0;
  double worst_front = 0, worst_column = 0;
  for (const Sample& sample : samples) {
    solver.advance(sample.t_s - solver.time_s());
    if (sample.is_front) {
      const double z_sim = front_x(solver) / a, Z = sample.reference;
      // Simulated fronts run ahead of the experiment (a free-slip floor, a gate that vanishes at
      // once): within 20% ahead and never more than 5% behind, for both methods.
      EXPECT_GT(z_sim, 0.95 * Z) << "t = " << sample.t_s << " s";
      EXPECT_LT(z_sim, 1.20 * Z) << "t = " << sample.t_s << " s";
      worst_front = std::max(worst_front, std::abs(z_sim - Z) / Z);
      ++fronts;
    } else {
      const double eta = column_height(solver) / (2 * a), reference = sample.reference;
      const double tau = sample.t_s * std::sqrt(g / a);
      // The collapse itself (tau <= 1.3) within 10%. Once the surge has left, the weakly
      // compressible column drains early, as its front runs ahead (20 particles across the
      // column): never more than 35% low or 10% high.
      if (tau <= 1.3 || incompressible) {
        EXPECT_NEAR(eta, reference, 0.10 * reference) << "tau = " << tau;
      } else {
        EXPECT_GT(eta, 0.65 * reference) << "tau = " << tau;
        EXPECT_LT(eta, 1.10 * reference) << "tau = " << tau;
      }
      worst_column = std::max(worst_column, std::abs(eta - reference) / reference);
      ++columns;
    }
  }
  EXPECT_GE(fronts, 10);
  EXPECT_GE(columns, 10);
  std::cout << "dam break (" << solver.method() << ", " << solver.steps() << " steps): worst relative front error "
            << worst_front * 100 << " %, residual column " << worst_column * 100 << " %\n";
  // Unlike the hydrostatic and momentum scenes, the last-resort wall clamp does act here, so it
  // is not asserted to stay at 0; it is reported: velocity noise out of the slab's plane (zero in
  // the experiment) throws particles into the walls' first layer faster than the flow itself
  // moves (sim_gpu/README.md, "Known").
  std::cout << "dam break: wall clamp events " << solver.clamped_particle_count() << "\n";
  EXPECT_EQ(solver.model().fluid.size(), count);      // mass conserved exactly
  for (float x : solver.model().fluid.x) ASSERT_LT(x, 0.6f);  // held by the far wall
  // DFSPH's walls are a volume map: nothing reaches them, the clamp stays idle.
  if (incompressible) {
    EXPECT_EQ(solver.clamped_particle_count(), 0u);
  }
}

}  // namespace

TEST(DamBreak, SurgeFrontAndResidualColumnFollowMartinMoyce1952) {
  check_dam_break("tests/sim_gpu/scenes/dam_break_slab.toml", false);
}

TEST(DamBreak, DfsphAtWaterViscosityFollowsMartinMoyce1952) {
  check_dam_break("tests/sim_gpu/scenes/dam_break_slab_dfsph.toml", true);
}
