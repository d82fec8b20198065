// bench_sim_cpu: steps per second of the CPU backend.
//  - fluid pool (§6.2.1, fig. 6a): a 1 x 1 m pool 0.25 m deep at ~8k, 16k, 32k, 64k particles,
//    1 and 2 threads; the 32k pool on dfsph too. A "scaling" record per solver gives the 32k
//    pool's time per step on 1 thread over that on 2 (same steps, same step size);
//  - fig. 6b: 25k particles, one floating sphere of 1k..20k particles, the pool shrinking to keep
//    the total;
//  - fig. 6c: 25k particles with 1..16 spheres sharing 8k body particles.
// Usage: bench_sim_cpu --out FILE.json [--quick]. Progress on stderr; JSON records on --out.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>
#include <unistd.h>
#include <vector>

#include "hapfluid/config/command_line.hpp"
#include "hapfluid/config/json_output.hpp"
#include "hapfluid/config/log.hpp"
#include "hapfluid/config/scene.hpp"
#include "hapfluid/sim/solver.hpp"
#include "hapfluid/sim/mesh_sampling.hpp"
#include "hapfluid/config/primitive_meshes.hpp"
#include "bench_scenes.hpp"

using namespace hapfluid;
using namespace hapfluid::sim;
using namespace hapfluid::sim::bench;

namespace {

std::vector<config::Json> records;

// Returns the wall time per step, ms.
double measure(const std::string& sweep, const config::Scene& scene, int threads, int steps,
               const config::Json& extra_params = config::Json::object()) {
  const std::unique_ptr<Solver> made = make_cpu_solver(build_model(scene), threads);
  Solver& solver = *made;
  const double dt = solver.stable_time_step();
  for (int i = 0; i < 3; ++i) solver.step(dt);  // warm-up: first touches, allocations
  const PhaseTimes before = solver.phase_times();
  const SolverIterations it0 = solver.iterations();
  const auto t0 = std::chrono::steady_clock::now();
  for (int i = 0; i < steps; ++i) solver.step(dt);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const PhaseTimes after = solver.phase_times();
  const SolverIterations it1 = solver.iterations();
  auto per_step = [&](std::uint64_t a, std::uint64_t b) { return static_cast<double>(a - b) / steps; };
  const auto& m = solver.model();
  const std::size_t fluid = m.fluid.size(), body = m.body_particles.size();
  const double ms = 1000 * wall / steps;
  auto phase = [&](double a, double b) { return 1000 * (a - b) / steps; };
  config::Json params = {{"backend", "cpu"}, {"sweep", sweep}, {"particles", fluid + body}, {"fluid_particles", fluid},
                         {"body_particles", body}, {"boundary_particles", m.wall_particle_count}, {"threads", threads},
                         {"solver", solver.method()}, {"dt_s", dt}};
  params.update(extra_params);
  records.push_back(config::bench_record(
      "bench_sim_cpu", std::move(params),
      {{"steps_per_s", steps / wall}, {"ms_per_step", ms}, {"particle_steps_per_s", steps * static_cast<double>(fluid + body) / wall},
       {"neighbour_search_ms", phase(after.neighbour_search_s, before.neighbour_search_s)},
       {"density_ms", phase(after.density_s, before.density_s)}, {"forces_ms", phase(after.forces_s, before.forces_s)},
       {"bodies_ms", phase(after.bodies_s, before.bodies_s)}, {"integration_ms", phase(after.integration_s, before.integration_s)},
       {"pressure_ms", phase(after.pressure_s, before.pressure_s)},
       {"density_iterations_per_step", per_step(it1.density_iterations, it0.density_iterations)},
       {"divergence_iterations_per_step", per_step(it1.divergence_iterations, it0.divergence_iterations)},
       {"viscosity_iterations_per_step", per_step(it1.viscosity_iterations, it0.viscosity_iterations)}}));
  log::info("%-5s %s %6zu particles (%zu body), %d thread(s): %7.2f ms/step, %6.1f steps/s "
            "[grid %.2f, density %.2f, pressure %.2f, forces %.2f, bodies %.2f, integrate %.2f ms]",
            sweep.c_str(), solver.method(), fluid + body, body, threads, ms, steps / wall,
            phase(after.neighbour_search_s, before.neighbour_search_s), phase(after.density_s, before.density_s),
            phase(after.pressure_s, before.pressure_s), phase(after.forces_s, before.forces_s),
            phase(after.bodies_s, before.bodies_s), phase(after.integration_s, before.integration_s));
  return ms;
}

// The pool of n particles on 1 and 2 threads; with `scaling`, a record of the speed-up too.
void measure_pool(const std::filesystem::path& dir, int n, bool dfsph, bool scaling, int steps) {
  const double ms_1 = measure("pool", pool_scene(dir, n, n, {}, dfsph), 1, steps);
  const double ms_2 = measure("pool", pool_scene(dir, n, n, {}, dfsph), 2, steps);
  if (!scaling) return;
  const char* solver = dfsph ? "dfsph" : "wcsph";
  records.push_back(config::bench_record(
      "bench_sim_cpu", {{"backend", "cpu"}, {"sweep", "scaling"}, {"solver", solver}, {"particles_requested", n}},
      {{"ms_per_step_1_thread", ms_1}, {"ms_per_step_2_threads", ms_2}, {"speedup_2_threads", ms_1 / ms_2}}));
  log::info("%s pool of %d, 2 threads are %.2fx one", solver, n, ms_1 / ms_2);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Steps per second of the CPU backend: fluid pools, fig. 6b and 6c; JSON records to --out.",
               "bench_sim_cpu"};
  config::apply_convention(app);
  std::string out;
  bool quick = false;
  app.add_option("--out", out, "JSON records (a list) to this file")->required();
  app.add_flag("--quick", quick, "the smallest sweep, for tests");
  if (const int code = config::parse_command_line(app, argc, argv); code >= 0) return code;
  const auto dir = std::getenv("BENCH_KEEP_DIR") ? std::filesystem::path(std::getenv("BENCH_KEEP_DIR"))
                                                : std::filesystem::temp_directory_path() / ("bench_sim_cpu_" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  const int steps = quick ? 5 : 30;
  try {
    // Fluid pool, fig. 6a.
    const std::vector<int> sizes = quick ? std::vector<int>{8000, 32000} : std::vector<int>{8000, 16000, 32000, 64000};
    for (int n : sizes) measure_pool(dir, n, false, n == 32000, steps);
    measure_pool(dir, 32000, true, true, steps);
    // Fig. 6b: one sphere of 1k..20k particles in a 25k-particle scene.
    const int total = 25000;
    const std::vector<int> sphere_sizes = quick ? std::vector<int>{5000} : std::vector<int>{1000, 2500, 5000, 10000, 20000};
    for (int n : sphere_sizes) {
      const double r = 0.15;
      std::vector<Body> bodies = {{0.5, 0.5, 0.2, r, sphere_spacing(n, r)}};
      measure("fig6b", matched_scene(dir, total, bodies), 2, steps,
              {{"bodies", 1}, {"body_particles_requested", n}});
    }
    // Fig. 6c: 1..16 spheres sharing 8k body particles in a 25k-particle scene.
    const std::vector<int> counts = quick ? std::vector<int>{4} : std::vector<int>{1, 2, 4, 8, 16};
    for (int k : counts) {
      const int per_row = static_cast<int>(std::ceil(std::sqrt(static_cast<double>(k))));
      const double cell = 1.0 / per_row, r = std::min(0.15, 0.35 * cell);
      const double spacing = sphere_spacing(8000 / k, r);
      std::vector<Body> bodies;
      for (int i = 0; i < k; ++i) bodies.push_back({(i % per_row + 0.5) * cell, (i / per_row + 0.5) * cell, 0.2, r, spacing});
      measure("fig6c", matched_scene(dir, total, bodies), 2, steps, {{"bodies", k}});
    }
  } catch (const std::exception& e) {
    log::Line(log::Level::error) << "" << e.what();
    std::filesystem::remove_all(dir);
    return 1;
  }
  std::filesystem::remove_all(dir);
  try {
    config::write_json_atomically(out, records);
  } catch (const std::exception& e) {
    log::Line(log::Level::error) << "" << e.what();
    return 1;
  }
  return 0;
}
