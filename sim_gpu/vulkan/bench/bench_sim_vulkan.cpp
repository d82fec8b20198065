// bench_sim_vulkan: steps per second of the Vulkan backend on the scenes of bench_sim_cpu (same
// definitions, so `make bench` puts the two backends side by side), with the per-pass GPU split
// from timestamp queries:
//  - pool (§6.2.1, fig. 6a): a 1 x 1 m pool 0.25 m deep at ~8k, 16k, 32k, 64k particles; each
//    also timed on the CPU backend (2 threads) in this process for the Vulkan/CPU ratio;
//  - fig6b: 25k particles, one floating sphere of 1k..20k particles;
//  - fig6c: 25k particles with 1..16 spheres sharing 8k body particles.
// Usage: bench_sim_vulkan --out FILE.json [--quick] [--validation]. Progress on stderr.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <unistd.h>
#include <vector>

#include "hapfluid/config/scene.hpp"
#include "hapfluid/sim/cpu_solver.hpp"
#include "hapfluid/sim/mesh_sampling.hpp"
#include "hapfluid/config/primitive_meshes.hpp"
#include "hapfluid/sim_vulkan/vulkan_solver.hpp"
#include "../../bench/bench_scenes.hpp"

using namespace hapfluid;
using namespace hapfluid::sim;
using namespace hapfluid::sim::bench;

namespace {

std::vector<std::string> records;

double cpu_ms_per_step(const SimulationModel& model, int steps) {
  CpuSolver solver(model, 2);
  const double dt = solver.stable_time_step();
  for (int i = 0; i < 3; ++i) solver.step(dt);
  const auto t0 = std::chrono::steady_clock::now();
  for (int i = 0; i < steps; ++i) solver.step(dt);
  return 1000 * std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() / steps;
}

void measure(const std::string& sweep, const config::Scene& scene, int steps, bool validation, bool with_cpu,
             const std::string& extra_params) {
  const SimulationModel model = build_model(scene);
  vulkan::VulkanSolverOptions options;
  options.context.validation = validation;
  vulkan::VulkanSolver solver(model, options);
  const double dt = solver.stable_time_step();
  solver.step_many(dt, 3);  // warm-up: first touches of every buffer
  const vulkan::PassTimes before = solver.pass_times();
  const auto t0 = std::chrono::steady_clock::now();
  // The steps of a published frame go in one submission (fluid-only scenes; with bodies every
  // step is two submissions around the host's body integration).
  solver.step_many(dt, steps);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const vulkan::PassTimes& after = solver.pass_times();
  const auto& m = solver.model();
  const std::size_t fluid = m.fluid.size(), body = m.body_particles.size();
  const double ms = 1000 * wall / steps;
  auto pass = [&](double a, double b) { return 1000 * (a - b) / steps; };
  const double cpu_ms = with_cpu ? cpu_ms_per_step(model, steps) : 0;
  char buf[1400];
  std::snprintf(buf, sizeof buf,
                "{\"bench\": \"bench_sim_vulkan\", \"params\": {\"backend\": \"vulkan\", \"sweep\": \"%s\", \"particles\": %zu, "
                "\"fluid_particles\": %zu, \"body_particles\": %zu, \"boundary_particles\": %zu, \"device\": \"%s\"%s}, "
                "\"metrics\": {\"steps_per_s\": %.3f, \"ms_per_step\": %.3f, \"particle_steps_per_s\": %.0f, "
                "\"sort_ms\": %.3f, \"density_ms\": %.3f, \"forces_ms\": %.3f, \"bodies_ms\": %.3f, "
                "\"integration_ms\": %.3f, \"reductions_ms\": %.3f%s}}",
                sweep.c_str(), fluid + body, fluid, body, m.wall_particle_count, solver.device().name.c_str(),
                extra_params.c_str(), steps / wall, ms, steps * static_cast<double>(fluid + body) / wall,
                pass(after.sort_s, before.sort_s), pass(after.density_s, before.density_s),
                pass(after.forces_s, before.forces_s), pass(after.bodies_s, before.bodies_s),
                pass(after.integration_s, before.integration_s), pass(after.reductions_s, before.reductions_s),
                with_cpu ? (", \"cpu_2_threads_ms_per_step\": " + std::to_string(cpu_ms) +
                            ", \"vulkan_over_cpu\": " + std::to_string(ms / cpu_ms))
                               .c_str()
                         : "");
  records.push_back(buf);
  std::fprintf(stderr,
               "bench_sim_vulkan: %-5s %6zu particles (%zu body) on %s: %7.2f ms/step, %6.1f steps/s "
               "[sort %.2f, density %.2f, forces %.2f, bodies %.2f, integrate %.2f, reductions %.2f ms]",
               sweep.c_str(), fluid + body, body, solver.device().name.c_str(), ms, steps / wall,
               pass(after.sort_s, before.sort_s), pass(after.density_s, before.density_s),
               pass(after.forces_s, before.forces_s), pass(after.bodies_s, before.bodies_s),
               pass(after.integration_s, before.integration_s), pass(after.reductions_s, before.reductions_s));
  if (with_cpu) std::fprintf(stderr, "; cpu backend, 2 threads: %.2f ms/step", cpu_ms);
  std::fprintf(stderr, "\n");
}

}  // namespace

int main(int argc, char** argv) {
  std::string out;
  bool quick = false, validation = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--out" && i + 1 < argc) out = argv[++i];
    else if (a == "--quick") quick = true;
    else if (a == "--validation") validation = true;
    else {
      std::cerr << "usage: bench_sim_vulkan --out FILE.json [--quick] [--validation]\n";
      return 2;
    }
  }
  if (out.empty()) {
    std::cerr << "bench_sim_vulkan: --out FILE.json is required\n";
    return 2;
  }
  const auto dir = std::filesystem::temp_directory_path() / ("bench_sim_vulkan_" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  const int steps = quick ? 5 : 30;
  try {
    const std::vector<int> sizes = quick ? std::vector<int>{8000, 32000} : std::vector<int>{8000, 16000, 32000, 64000};
    for (int n : sizes) measure("pool", pool_scene(dir, n, n, {}), steps, validation, true, "");
    const int total = 25000;
    const std::vector<int> sphere_sizes = quick ? std::vector<int>{5000} : std::vector<int>{1000, 2500, 5000, 10000, 20000};
    for (int n : sphere_sizes) {
      const double r = 0.15;
      const std::vector<Body> bodies = {{0.5, 0.5, 0.2, r, sphere_spacing(n, r)}};
      measure("fig6b", matched_scene(dir, total, bodies), steps, validation, false, ", \"bodies\": 1, \"body_particles_requested\": " + std::to_string(n));
    }
    const std::vector<int> counts = quick ? std::vector<int>{4} : std::vector<int>{1, 2, 4, 8, 16};
    for (int k : counts) {
      const int per_row = static_cast<int>(std::ceil(std::sqrt(static_cast<double>(k))));
      const double cell = 1.0 / per_row, r = std::min(0.15, 0.35 * cell);
      const double spacing = sphere_spacing(8000 / k, r);
      std::vector<Body> bodies;
      for (int i = 0; i < k; ++i) bodies.push_back({(i % per_row + 0.5) * cell, (i / per_row + 0.5) * cell, 0.2, r, spacing});
      measure("fig6c", matched_scene(dir, total, bodies), steps, validation, false,
              ", \"bodies\": " + std::to_string(k));
    }
  } catch (const std::exception& e) {
    std::cerr << "bench_sim_vulkan: " << e.what() << "\n";
    std::filesystem::remove_all(dir);
    return 1;
  }
  std::filesystem::remove_all(dir);
  std::ofstream f(out + ".part");
  f << "[\n";
  for (std::size_t i = 0; i < records.size(); ++i) f << "  " << records[i] << (i + 1 < records.size() ? ",\n" : "\n");
  f << "]\n";
  f.close();
  std::filesystem::rename(out + ".part", out);
  return 0;
}
