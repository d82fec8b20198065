// bench_sim_vulkan: steps per second of the Vulkan backend on the fluid pool of §6.2.1 at about
// 8k, 16k, 32k and 64k fluid particles, with the per-pass GPU split (timestamp queries).
//   bench_sim_vulkan --out FILE.json [--quick] [--seconds S] [--validation]
// Records: {"bench": "sim_vulkan", "params": {"backend": "vulkan", "scene", "particles",
// "device"}, "metrics": {"steps_per_s", "ms_per_step", "particle_steps_per_s", "<pass>_ms"}}.
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "hapfluid/config/scene.hpp"
#include "hapfluid/sim/model.hpp"
#include "hapfluid/sim_vulkan/vulkan_solver.hpp"

namespace hs = hapfluid::sim;
namespace hv = hapfluid::sim::vulkan;

namespace {

// A pool: a block of n x n x n/2 fluid particles (spacing 1 cm) at rest in a closed box twice
// as high, as in the paper's fluid pool. h = 2 spacing, c = 10 sqrt(g H).
std::string pool_scene(int n) {
  const double s = 0.01, side = n * s, depth = (n / 2) * s;
  std::ostringstream t;
  t << "name = \"pool_" << n << "\"\nduration_s = 1.0\n"
    << "[domain]\nmin_m = [0.0, 0.0, 0.0]\nmax_m = [" << side << ", " << side << ", " << 2 * depth << "]\n"
    << "[fluid]\nparticle_spacing_m = " << s << "\nspeed_of_sound_m_s = 15.0\nviscosity_pa_s = 0.01\n"
    << "[[fluid.blocks]]\nmin_m = [0.0, 0.0, 0.0]\nmax_m = [" << side << ", " << side << ", " << depth << "]\n"
    << "[time]\ncfl = 0.4\nframe_rate_hz = 60.0\n";
  return t.str();
}

struct Record {
  std::string scene, device;
  std::size_t particles = 0;
  double steps_per_s = 0, ms_per_step = 0;
  hv::PassTimes passes;
};

Record run(int n, double seconds, bool validation) {
  const auto scene = hapfluid::config::parse_scene(pool_scene(n), "bench_sim_vulkan pool");
  hv::VulkanSolverOptions options;
  options.context.validation = validation;
  hv::VulkanSolver solver(hs::build_model(scene), options);
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
  const double steps = static_cast<double>(solver.steps() - steps0);
  r.steps_per_s = steps / wall;
  r.ms_per_step = 1000.0 * wall / steps;
  const hv::PassTimes& after = solver.pass_times();
  r.passes.sort_s = (after.sort_s - before.sort_s) / steps;
  r.passes.density_s = (after.density_s - before.density_s) / steps;
  r.passes.forces_s = (after.forces_s - before.forces_s) / steps;
  r.passes.integration_s = (after.integration_s - before.integration_s) / steps;
  r.passes.reductions_s = (after.reductions_s - before.reductions_s) / steps;
  return r;
}

std::string json(const std::vector<Record>& records) {
  std::ostringstream j;
  j << "[\n";
  for (std::size_t i = 0; i < records.size(); ++i) {
    const Record& r = records[i];
    j << "  {\"bench\": \"sim_vulkan\", \"params\": {\"backend\": \"vulkan\", \"scene\": \"" << r.scene
      << "\", \"particles\": " << r.particles << ", \"device\": \"" << r.device << "\"}, \"metrics\": {"
      << "\"steps_per_s\": " << r.steps_per_s << ", \"ms_per_step\": " << r.ms_per_step
      << ", \"particle_steps_per_s\": " << r.steps_per_s * static_cast<double>(r.particles)
      << ", \"sort_ms\": " << 1000 * r.passes.sort_s << ", \"density_ms\": " << 1000 * r.passes.density_s
      << ", \"forces_ms\": " << 1000 * r.passes.forces_s << ", \"integration_ms\": " << 1000 * r.passes.integration_s
      << ", \"reductions_ms\": " << 1000 * r.passes.reductions_s << "}}" << (i + 1 < records.size() ? "," : "") << "\n";
  }
  j << "]\n";
  return j.str();
}

}  // namespace

int main(int argc, char** argv) {
  std::string out;
  bool quick = false, validation = false;
  double seconds = 3.0;
  std::vector<int> sizes = {20, 25, 32, 40, 50};  // 4k, 8k, 16k, 32k, 62.5k fluid particles
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--out" && i + 1 < argc) out = argv[++i];
    else if (a == "--quick") quick = true;
    else if (a == "--validation") validation = true;
    else if (a == "--seconds" && i + 1 < argc) seconds = std::atof(argv[++i]);
    else if (a == "--sizes" && i + 1 < argc) {
      sizes.clear();
      std::stringstream list(argv[++i]);
      for (std::string item; std::getline(list, item, ',');) sizes.push_back(std::atoi(item.c_str()));
    } else {
      std::cerr << "usage: bench_sim_vulkan --out FILE.json [--quick] [--seconds S] [--sizes 25,32,40] [--validation]\n";
      return 2;
    }
  }
  if (quick) seconds = 1.0, sizes = {25, 40};
  std::vector<Record> records;
  try {
    for (int n : sizes) {
      const Record r = run(n, seconds, validation);
      std::fprintf(stderr,
                   "bench_sim_vulkan: %-9s %6zu particles on %s: %6.1f steps/s, %6.2f ms/step "
                   "(sort %.2f, density %.2f, forces %.2f, integration %.2f, reductions %.2f ms)\n",
                   r.scene.c_str(), r.particles, r.device.c_str(), r.steps_per_s, r.ms_per_step, 1000 * r.passes.sort_s,
                   1000 * r.passes.density_s, 1000 * r.passes.forces_s, 1000 * r.passes.integration_s,
                   1000 * r.passes.reductions_s);
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
