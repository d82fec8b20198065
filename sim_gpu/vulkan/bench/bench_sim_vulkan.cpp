// bench_sim_vulkan: steps per second of the Vulkan backend on the scenes of bench_sim_cpu (same
// definitions, so `make bench` puts the two backends side by side), with the per-pass GPU split
// from timestamp queries:
//  - pool (§6.2.1, fig. 6a): a 1 x 1 m pool 0.25 m deep at ~8k, 16k, 32k, 64k particles; each
//    also timed on the CPU backend (2 threads) in this process for the Vulkan/CPU ratio;
//  - pool_dfsph: the same pool at 8k and 32k on the incompressible solver, against the CPU's;
//  - fig6b: 25k particles, one floating sphere of 1k..20k particles;
//  - fig6c: 25k particles with 1..16 spheres sharing 8k body particles.
// Usage: bench_sim_vulkan --out FILE.json [--quick] [--validation]. Progress on stderr.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <string>
#include <unistd.h>
#include <vector>

#include "hapfluid/config/command_line.hpp"
#include "hapfluid/config/json_output.hpp"
#include "hapfluid/config/log.hpp"
#include "hapfluid/config/scene.hpp"
#include "hapfluid/sim/cpu_solver.hpp"
#include "hapfluid/sim/mesh_sampling.hpp"
#include "hapfluid/config/primitive_meshes.hpp"
#include "hapfluid/sim/solver.hpp"
#include "hapfluid/sim_vulkan/iteration_budget.hpp"
#include "hapfluid/sim_vulkan/vulkan_solver.hpp"
#include "../../bench/bench_scenes.hpp"

using namespace hapfluid;
using namespace hapfluid::sim;
using namespace hapfluid::sim::bench;

namespace {

std::vector<config::Json> records;

// The CPU solver of the scene's method, 2 threads, the same steps of `dt` as the device took.
double cpu_ms_per_step(const SimulationModel& model, double dt, int warm_up, int steps) {
  const auto solver = make_cpu_solver(model, 2);
  for (int i = 0; i < warm_up; ++i) solver->step(dt);
  const auto t0 = std::chrono::steady_clock::now();
  for (int i = 0; i < steps; ++i) solver->step(dt);
  return 1000 * std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() / steps;
}

void measure(const std::string& sweep, const config::Scene& scene, int steps, bool validation, bool with_cpu,
             const config::Json& extra_params = config::Json::object()) {
  const SimulationModel model = build_model(scene);
  vulkan::VulkanSolverOptions options;
  options.context.validation = validation;
  vulkan::VulkanSolver solver(model, options);
  const double dt = solver.stable_time_step();
  // Warm-up: first touches of every buffer; for the incompressible solver, the submissions its
  // iteration budgets learn from (iteration_budget.hpp), one step each, as a live run makes them.
  const bool dfsph = model.params.solver == config::PressureSolver::dfsph;
  const int warm_up = dfsph ? vulkan::IterationBudget::kWindow : 3;
  if (dfsph) {
    for (int i = 0; i < warm_up; ++i) solver.step(dt);
  } else {
    solver.step_many(dt, warm_up);
  }
  const vulkan::PassTimes before = solver.pass_times();
  const vulkan::StepWork work_before = solver.work();
  const SolverIterations its_before = solver.iterations();
  const auto t0 = std::chrono::steady_clock::now();
  // The steps of a published frame go in one submission (fluid-only scenes; with bodies every
  // step is two submissions around the host's body integration).
  solver.step_many(dt, steps);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const vulkan::PassTimes& after = solver.pass_times();
  const vulkan::StepWork& work = solver.work();
  const SolverIterations& its = solver.iterations();
  auto per_step = [&](std::uint64_t a, std::uint64_t b) { return static_cast<double>(a - b) / steps; };
  const auto& m = solver.model();
  const std::size_t fluid = m.fluid.size(), body = m.body_particles.size();
  const double ms = 1000 * wall / steps;
  auto pass = [&](double a, double b) { return 1000 * (a - b) / steps; };
  const double cpu_ms = with_cpu ? cpu_ms_per_step(model, dt, warm_up, steps) : 0;
  config::Json params = {{"backend", "vulkan"}, {"sweep", sweep}, {"solver", solver.method()},
                         {"particles", fluid + body}, {"fluid_particles", fluid},
                         {"body_particles", body}, {"boundary_particles", m.wall_particle_count},
                         {"device", solver.device().name}};
  params.update(extra_params);
  config::Json metrics = {{"steps_per_s", steps / wall}, {"ms_per_step", ms},
                          {"particle_steps_per_s", steps * static_cast<double>(fluid + body) / wall},
                          {"sort_ms", pass(after.sort_s, before.sort_s)}, {"density_ms", pass(after.density_s, before.density_s)},
                          {"forces_ms", pass(after.forces_s, before.forces_s)}, {"bodies_ms", pass(after.bodies_s, before.bodies_s)},
                          {"integration_ms", pass(after.integration_s, before.integration_s)},
                          {"pressure_solve_ms", pass(after.pressure_s, before.pressure_s)},
                          {"reductions_ms", pass(after.reductions_s, before.reductions_s)},
                          // What a step asks of the device and the host (the steps of a frame in
                          // one submission): recorded dispatches (indirect ones may run empty),
                          // barriers, submissions and fence waits.
                          {"dispatches_per_step", per_step(work.dispatches, work_before.dispatches)},
                          {"indirect_dispatches_per_step", per_step(work.indirect_dispatches, work_before.indirect_dispatches)},
                          {"barriers_per_step", per_step(work.barriers, work_before.barriers)},
                          {"submissions_per_step", per_step(work.submissions, work_before.submissions)},
                          {"host_waits_per_step", per_step(work.host_waits, work_before.host_waits)}};
  if (dfsph) {
    metrics["density_iterations_per_step"] = per_step(its.density_iterations, its_before.density_iterations);
    metrics["divergence_iterations_per_step"] = per_step(its.divergence_iterations, its_before.divergence_iterations);
    metrics["budget_overruns"] = its.budget_overruns - its_before.budget_overruns;
  }
  if (with_cpu) {
    metrics["cpu_2_threads_ms_per_step"] = cpu_ms;
    metrics["vulkan_over_cpu"] = ms / cpu_ms;
  }
  records.push_back(config::bench_record("bench_sim_vulkan", std::move(params), std::move(metrics)));
  char cpu[64] = "";
  if (with_cpu) std::snprintf(cpu, sizeof cpu, "; cpu backend, 2 threads: %.2f ms/step", cpu_ms);
  log::info("%-5s %6zu particles (%zu body) on %s: %7.2f ms/step, %6.1f steps/s "
            "[sort %.2f, density %.2f, forces %.2f, bodies %.2f, integrate %.2f, reductions %.2f ms]%s",
            sweep.c_str(), fluid + body, body, solver.device().name.c_str(), ms, steps / wall,
            pass(after.sort_s, before.sort_s), pass(after.density_s, before.density_s),
            pass(after.forces_s, before.forces_s), pass(after.bodies_s, before.bodies_s),
            pass(after.integration_s, before.integration_s), pass(after.reductions_s, before.reductions_s), cpu);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Steps per second of the Vulkan backend on the scenes of bench_sim_cpu; JSON records to --out.",
               "bench_sim_vulkan"};
  config::apply_convention(app);
  std::string out;
  bool quick = false, validation = false;
  app.add_option("--out", out, "JSON records (a list) to this file")->required();
  app.add_flag("--quick", quick, "the smallest sweep, for tests");
  app.add_flag("--validation", validation, "run with the Khronos validation layer");
  if (const int code = config::parse_command_line(app, argc, argv); code >= 0) return code;
  const auto dir = std::filesystem::temp_directory_path() / ("bench_sim_vulkan_" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  const int steps = quick ? 5 : 30;
  try {
    const std::vector<int> sizes = quick ? std::vector<int>{8000, 32000} : std::vector<int>{8000, 16000, 32000, 64000};
    for (int n : sizes) measure("pool", pool_scene(dir, n, n, {}), steps, validation, true);
    // The incompressible solver at water's viscosity (the default method), against the CPU's.
    const std::vector<int> dfsph_sizes = quick ? std::vector<int>{8000} : std::vector<int>{8000, 32000};
    for (int n : dfsph_sizes) measure("pool_dfsph", pool_scene(dir, n, n, {}, true), steps, validation, true);
    const int total = 25000;
    const std::vector<int> sphere_sizes = quick ? std::vector<int>{5000} : std::vector<int>{1000, 2500, 5000, 10000, 20000};
    for (int n : sphere_sizes) {
      const double r = 0.15;
      const std::vector<Body> bodies = {{0.5, 0.5, 0.2, r, sphere_spacing(n, r)}};
      measure("fig6b", matched_scene(dir, total, bodies), steps, validation, false,
              {{"bodies", 1}, {"body_particles_requested", n}});
    }
    const std::vector<int> counts = quick ? std::vector<int>{4} : std::vector<int>{1, 2, 4, 8, 16};
    for (int k : counts) {
      const int per_row = static_cast<int>(std::ceil(std::sqrt(static_cast<double>(k))));
      const double cell = 1.0 / per_row, r = std::min(0.15, 0.35 * cell);
      const double spacing = sphere_spacing(8000 / k, r);
      std::vector<Body> bodies;
      for (int i = 0; i < k; ++i) bodies.push_back({(i % per_row + 0.5) * cell, (i / per_row + 0.5) * cell, 0.2, r, spacing});
      measure("fig6c", matched_scene(dir, total, bodies), steps, validation, false, {{"bodies", k}});
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
