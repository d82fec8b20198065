// bench_sim_vulkan: steps per second of the Vulkan backend, with the per-pass GPU split
// (timestamp queries), on the paper's benchmark scenes:
//  - the fluid pool of §6.2.1 at about 8k, 16k, 32k and 64k fluid particles, each also run on
//    the CPU backend (2 threads) in the same process for the ratio the issue asks for;
//  - fig. 6b: a 25k-particle pool with one rigid sphere of 1k..20k particles;
//  - fig. 6c: the same pool with 1..16 rigid spheres of ~1k particles.
//   bench_sim_vulkan --out FILE.json [--quick] [--seconds S] [--sizes 26,40] [--validation]
// Records: {"bench": "sim_vulkan", "params": {"backend": "vulkan", "scene", "particles",
// "body_particles", "bodies", "device"}, "metrics": {"steps_per_s", "ms_per_step",
// "particle_steps_per_s", "<pass>_ms", and for the pools "cpu_ms_per_step", "vulkan_over_cpu"}}.
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "hapfluid/config/scene.hpp"
#include "hapfluid/sim/cpu_solver.hpp"
#include "hapfluid/sim/model.hpp"
#include "hapfluid/sim_vulkan/vulkan_solver.hpp"

namespace hs = hapfluid::sim;
namespace hv = hapfluid::sim::vulkan;

namespace {

// A pool: a block of n x n x n/2 fluid particles (spacing 1 cm) at rest in a closed box twice
// as high, as in the paper's fluid pool. h = 2 spacing, c = 15 m/s; `bodies` is appended.
std::string pool_scene(const std::string& name, int n, const std::string& bodies = "") {
  const double s = 0.01, side = n * s, depth = (n / 2) * s;
  std::ostringstream t;
  t << "name = \"" << name << "\"\nduration_s = 1.0\n"
    << "[domain]\nmin_m = [0.0, 0.0, 0.0]\nmax_m = [" << side << ", " << side << ", " << 2 * depth << "]\n"
    << "[fluid]\nparticle_spacing_m = " << s << "\nspeed_of_sound_m_s = 15.0\nviscosity_pa_s = 0.01\n"
    << "[[fluid.blocks]]\nmin_m = [0.0, 0.0, 0.0]\nmax_m = [" << side << ", " << side << ", " << depth << "]\n"
    << "[time]\ncfl = 0.4\nframe_rate_hz = 60.0\n"
    << bodies;
  return t.str();
}

// A floating sphere (config/meshes/sphere.obj, radius 0.05 m at scale 1) of density 500 kg/m^3.
std::string sphere_body(const std::string& name, double x, double y, double z, double scale, double spacing) {
  std::ostringstream t;
  t << "[[bodies]]\nname = \"" << name << "\"\nmesh = \"" << HAPFLUID_SOURCE_DIR << "/config/meshes/sphere.obj\"\n"
    << "scale = " << scale << "\nposition_m = [" << x << ", " << y << ", " << z << "]\ndensity_kg_m3 = 500.0\n"
    << "sampling_spacing_m = " << spacing << "\n";
  return t.str();
}

struct Record {
  std::string scene, device;
  std::size_t particles = 0, body_particles = 0, bodies = 0;
  double steps_per_s = 0, ms_per_step = 0, cpu_ms_per_step = 0;
  hv::PassTimes passes;
};

double cpu_ms_per_step(const hs::SimulationModel& model, double seconds) {
  hs::CpuSolver solver(model, 2);
  const double frame = 1.0 / solver.params().frame_rate_hz;
  solver.advance(frame);
  const std::uint64_t steps0 = solver.steps();
  const auto t0 = std::chrono::steady_clock::now();
  double wall = 0;
  do {
    solver.advance(frame);
    wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  } while (wall < seconds);
  return 1000.0 * wall / static_cast<double>(solver.steps() - steps0);
}

Record run(const std::string& scene_text, double seconds, bool validation, bool with_cpu) {
  const auto scene = hapfluid::config::parse_scene(scene_text, "bench_sim_vulkan scene");
  const hs::SimulationModel model = hs::build_model(scene);
  hv::VulkanSolverOptions options;
  options.context.validation = validation;
  hv::VulkanSolver solver(model, options);
  const double frame = 1.0 / solver.params().frame_rate_hz;
  solver.advance(frame);  // warm-up: pipelines, first sort of a fresh lattice
  const hv::PassTimes before = solver.pass_times();
  const std::uint64_t steps0 = solver.steps();
  const auto t0 = std::chrono::steady_clock::now();
  double wall = 0;
  do {
    solver.advance(frame);
    wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  } while (wall < seconds);
  Record r;
  r.scene = scene.name;
  r.device = solver.device().name;
  r.particles = solver.model().fluid.size();
  r.body_particles = solver.model().body_particles.size();
  r.bodies = solver.model().bodies.size();
  const double steps = static_cast<double>(solver.steps() - steps0);
  r.steps_per_s = steps / wall;
  r.ms_per_step = 1000.0 * wall / steps;
  const hv::PassTimes& after = solver.pass_times();
  r.passes.sort_s = (after.sort_s - before.sort_s) / steps;
  r.passes.density_s = (after.density_s - before.density_s) / steps;
  r.passes.forces_s = (after.forces_s - before.forces_s) / steps;
  r.passes.integration_s = (after.integration_s - before.integration_s) / steps;
  r.passes.reductions_s = (after.reductions_s - before.reductions_s) / steps;
  r.passes.bodies_s = (after.bodies_s - before.bodies_s) / steps;
  if (with_cpu) r.cpu_ms_per_step = cpu_ms_per_step(model, seconds);
  return r;
}

std::string json(const std::vector<Record>& records) {
  std::ostringstream j;
  j << "[\n";
  for (std::size_t i = 0; i < records.size(); ++i) {
    const Record& r = records[i];
    j << "  {\"bench\": \"sim_vulkan\", \"params\": {\"backend\": \"vulkan\", \"scene\": \"" << r.scene
      << "\", \"particles\": " << r.particles << ", \"body_particles\": " << r.body_particles
      << ", \"bodies\": " << r.bodies << ", \"device\": \"" << r.device << "\"}, \"metrics\": {"
      << "\"steps_per_s\": " << r.steps_per_s << ", \"ms_per_step\": " << r.ms_per_step
      << ", \"particle_steps_per_s\": " << r.steps_per_s * static_cast<double>(r.particles)
      << ", \"sort_ms\": " << 1000 * r.passes.sort_s << ", \"density_ms\": " << 1000 * r.passes.density_s
      << ", \"forces_ms\": " << 1000 * r.passes.forces_s << ", \"integration_ms\": " << 1000 * r.passes.integration_s
      << ", \"bodies_ms\": " << 1000 * r.passes.bodies_s << ", \"reductions_ms\": " << 1000 * r.passes.reductions_s;
    if (r.cpu_ms_per_step > 0)
      j << ", \"cpu_ms_per_step\": " << r.cpu_ms_per_step << ", \"vulkan_over_cpu\": " << r.ms_per_step / r.cpu_ms_per_step;
    j << "}}" << (i + 1 < records.size() ? "," : "") << "\n";
  }
  j << "]\n";
  return j.str();
}

}  // namespace

int main(int argc, char** argv) {
  std::string out;
  bool quick = false, validation = false;
  double seconds = 2.0;
  std::vector<int> sizes = {26, 32, 40, 50};  // 8.8k, 16k, 32k, 62.5k fluid particles
  std::vector<double> sphere_spacings = {0.012, 0.0085, 0.0054, 0.004, 0.0028};  // ~1k, 2k, 5k, 10k, 20k particles
  std::vector<int> body_counts = {1, 2, 4, 8, 16};
  bool sweeps = true;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--out" && i + 1 < argc) out = argv[++i];
    else if (a == "--quick") quick = true;
    else if (a == "--validation") validation = true;
    else if (a == "--seconds" && i + 1 < argc) seconds = std::atof(argv[++i]);
    else if (a == "--no-sweeps") sweeps = false;
    else if (a == "--sizes" && i + 1 < argc) {
      sizes.clear();
      std::stringstream list(argv[++i]);
      for (std::string item; std::getline(list, item, ',');) sizes.push_back(std::atoi(item.c_str()));
    } else {
      std::cerr << "usage: bench_sim_vulkan --out FILE.json [--quick] [--seconds S] [--sizes 26,32,40] [--no-sweeps] "
                   "[--validation]\n";
      return 2;
    }
  }
  if (quick) seconds = 1.0, sizes = {26, 40}, sphere_spacings = {0.012, 0.004}, body_counts = {1, 8};
  std::vector<std::string> scenes;
  std::vector<bool> with_cpu;
  for (int n : sizes) scenes.push_back(pool_scene("pool_" + std::to_string(n), n)), with_cpu.push_back(true);
  if (sweeps) {
    // fig. 6b: 25k fluid particles (37 x 37 x 18) and one sphere of radius 0.1 m, half immersed.
    for (double s : sphere_spacings) {
      char name[64];
      std::snprintf(name, sizeof name, "fig6b_sphere_%.4f", s);
      scenes.push_back(pool_scene(name, 37, sphere_body("sphere", 0.185, 0.185, 0.18, 2.0, s)));
      with_cpu.push_back(false);
    }
    // fig. 6c: the same pool with k spheres of radius 0.04 m (~1k particles each) on a 4 x 4 grid.
    for (int k : body_counts) {
      std::string bodies;
      for (int b = 0; b < k; ++b)
        bodies += sphere_body("sphere_" + std::to_string(b), 0.05 + 0.09 * (b % 4), 0.05 + 0.09 * (b / 4), 0.18, 0.8, 0.005);
      scenes.push_back(pool_scene("fig6c_bodies_" + std::to_string(k), 37, bodies));
      with_cpu.push_back(false);
    }
  }
  std::vector<Record> records;
  try {
    for (std::size_t k = 0; k < scenes.size(); ++k) {
      const Record r = run(scenes[k], seconds, validation, with_cpu[k]);
      std::fprintf(stderr,
                   "bench_sim_vulkan: %-22s %6zu fluid + %5zu body particles on %s: %6.1f steps/s, %6.2f ms/step "
                   "(sort %.2f, density %.2f, forces %.2f, bodies %.2f, integration %.2f, reductions %.2f ms)",
                   r.scene.c_str(), r.particles, r.body_particles, r.device.c_str(), r.steps_per_s, r.ms_per_step,
                   1000 * r.passes.sort_s, 1000 * r.passes.density_s, 1000 * r.passes.forces_s, 1000 * r.passes.bodies_s,
                   1000 * r.passes.integration_s, 1000 * r.passes.reductions_s);
      if (r.cpu_ms_per_step > 0) std::fprintf(stderr, "; cpu backend (2 threads) %.2f ms/step", r.cpu_ms_per_step);
      std::fprintf(stderr, "\n");
      records.push_back(r);
    }
  } catch (const std::exception& e) {
    std::cerr << "bench_sim_vulkan: " << e.what() << "\n";
    return 1;
  }
  const std::string text = json(records);
  if (out.empty()) {
    std::cout << text;
  } else {
    std::ofstream(out) << text;
  }
  return 0;
}
