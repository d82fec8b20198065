// Neighbour search must find exactly the particles within h (a missed neighbour is a missing
// force), and a run must be bit-for-bit repeatable for a given thread count: the Vulkan backend
// and every regression comparison rely on it.
#include <gtest/gtest.h>

#include <cstring>
#include <random>
#include <set>

#include "hapfluid/sim/neighbour_grid.hpp"
#include "test_support.hpp"

using namespace hapfluid::sim;
namespace config = hapfluid::config;

TEST(NeighbourGrid, FindsExactlyTheParticlesWithinTheSupportRadius) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(0.0f, 0.3f);
  const std::size_t n = 3000;
  std::vector<float> x(n), y(n), z(n);
  for (std::size_t i = 0; i < n; ++i) x[i] = u(rng), y[i] = u(rng), z[i] = u(rng);
  const float h = 0.025f, lo[3] = {0, 0, 0}, hi[3] = {0.3f, 0.3f, 0.3f};
  const GridGeometry g = make_grid(lo, hi, h);
  CellSort sort;
  sort.sort(g, x.data(), y.data(), z.data(), n);
  for (std::size_t i = 0; i < n; i += 37) {
    std::set<std::uint32_t> found, expected;
    for_each_neighbour_run(g, sort.cell_start.data(), x[i], y[i], z[i], [&](std::uint32_t b, std::uint32_t e) {
      for (std::uint32_t k = b; k < e; ++k) {
        const std::uint32_t j = sort.order[k];
        const float dx = x[i] - x[j], dy = y[i] - y[j], dz = z[i] - z[j];
        if (dx * dx + dy * dy + dz * dz < h * h) found.insert(j);
      }
    });
    for (std::size_t j = 0; j < n; ++j) {
      const float dx = x[i] - x[j], dy = y[i] - y[j], dz = z[i] - z[j];
      if (dx * dx + dy * dy + dz * dz < h * h) expected.insert(static_cast<std::uint32_t>(j));
    }
    EXPECT_EQ(found, expected) << "particle " << i;
  }
}

TEST(NeighbourGrid, CountingSortIsStable) {
  // Particles of one cell keep index order: the order the Vulkan backend must reproduce.
  std::vector<float> x = {0.01f, 0.5f, 0.011f, 0.012f}, y(4, 0.01f), z(4, 0.01f);
  const float lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
  CellSort sort;
  sort.sort(make_grid(lo, hi, 0.1f), x.data(), y.data(), z.data(), 4);
  EXPECT_EQ(sort.order, (std::vector<std::uint32_t>{0, 2, 3, 1}));
}

namespace {

const char* kSplashScene = R"(
name = "splash"
[domain]
min_m = [0.0, 0.0, 0.0]
max_m = [0.16, 0.08, 0.16]
[fluid]
solver = "wcsph"
particle_spacing_m = 0.008
speed_of_sound_m_s = 12.0
viscosity_pa_s = 0.2
[[fluid.blocks]]
min_m = [0.0, 0.0, 0.0]
max_m = [0.06, 0.08, 0.12]
[[bodies]]
name = "ball"
mesh = "ball.obj"
position_m = [0.11, 0.04, 0.05]
density_kg_m3 = 700.0
[time]
cfl = 0.2
)";

// Simulated time of each determinism run (0.1 s: ~400 steps). The ThreadSanitizer build of
// this test (test_sim_determinism_tsan), ~20 times slower, runs 0.02 s: every pass and every
// hand-off of the thread pool still runs hundreds of times, which is what a race needs.
#ifndef HAPFLUID_DETERMINISM_RUN_S
#define HAPFLUID_DETERMINISM_RUN_S 0.1
#endif
constexpr double kRunSeconds = HAPFLUID_DETERMINISM_RUN_S;

std::vector<float> snapshot(const Solver& s) {
  const auto& f = s.model().fluid;
  std::vector<float> out;
  for (const auto* v : {&f.x, &f.y, &f.z, &f.vx, &f.vy, &f.vz, &f.pressure}) out.insert(out.end(), v->begin(), v->end());
  for (const auto& b : s.model().bodies)
    for (double d : {b.position.x, b.position.y, b.position.z, b.orientation.w, b.fluid_force.x})
      out.push_back(static_cast<float>(d));
  return out;
}

}  // namespace

TEST(Determinism, SameSceneTwiceWithTwoThreadsIsBitForBitEqual) {
  const auto dir = test::temp_dir("determinism");
  const auto scene = test::write_scene(dir, kSplashScene, {{"ball.obj", test::sphere_mesh(0.025, 2)}});
  std::vector<float> runs[2];
  for (auto& out : runs) {
    CpuSolver solver(build_model(scene), 2);
    test::run_for(solver, kRunSeconds);
    out = snapshot(solver);
  }
  ASSERT_EQ(runs[0].size(), runs[1].size());
  EXPECT_EQ(std::memcmp(runs[0].data(), runs[1].data(), runs[0].size() * sizeof(float)), 0);
  // One thread computes the same sums in the same order per particle: identical too.
  CpuSolver single(build_model(scene), 1);
  test::run_for(single, kRunSeconds);
  const auto one = snapshot(single);
  EXPECT_EQ(std::memcmp(runs[0].data(), one.data(), one.size() * sizeof(float)), 0);
  std::filesystem::remove_all(dir);
}

// The incompressible solver too: its passes write per slot (thread_pool.hpp), its sums of the
// solve errors add the slots in order, so any thread count gives the same iterations and the
// same state. The scene takes the implicit viscosity's conjugate gradients and XSPH as well.
TEST(Determinism, DfsphGivesTheSameStateOnOneAndTwoThreads) {
  const auto dir = test::temp_dir("determinism_dfsph");
  std::string text = kSplashScene;
  text.replace(text.find("solver = \"wcsph\"\n"), 16, "solver = \"dfsph\"\nxsph_fraction = 0.05\nsettle_s = 0.02\n");
  const auto scene = test::write_scene(dir, text, {{"ball.obj", test::sphere_mesh(0.025, 2)}});
  std::vector<float> runs[4];
  for (int k = 0; k < 4; ++k) {
    const auto solver = make_cpu_solver(build_model(scene), k == 2 ? 1 : 2);
    ASSERT_STREQ(solver->method(), "dfsph");
    if (k < 3) {
      test::run_for(*solver, kRunSeconds);
    } else {
      // As a live sim choosing its thread count as it runs (live/thread_choice.hpp): one and two
      // threads in turn, step by step.
      const int frames = static_cast<int>(std::lround(kRunSeconds / 0.01));
      for (int f = 0; f < frames; ++f)
        solver->advance(0.01, [&](double) { solver->set_active_threads(solver->steps() % 2 == 0 ? 1 : 2); });
      EXPECT_EQ(solver->threads(), 2);
    }
    solver->sync_and_check_finite();
    runs[k] = snapshot(*solver);
  }
  EXPECT_EQ(std::memcmp(runs[0].data(), runs[1].data(), runs[0].size() * sizeof(float)), 0) << "two threads, twice";
  EXPECT_EQ(std::memcmp(runs[0].data(), runs[2].data(), runs[0].size() * sizeof(float)), 0) << "two threads and one";
  EXPECT_EQ(std::memcmp(runs[0].data(), runs[3].data(), runs[0].size() * sizeof(float)), 0) << "one and two in turn";
  std::filesystem::remove_all(dir);
}
