// Live-mode speed of each backend on the shipped live scenes: what `haptic-sim --live --backend
// auto` decides on (live_backend.hpp), measured the same way (probe_backend: the scene's start,
// devices at their start pose, after warm-up steps) but for longer. A scene runs in real time
// when steps_per_s >= needed_steps_per_s, i.e. real_time_factor >= 1.
//
// Usage: bench_live_backends --out FILE.json [--quick]. Progress on stderr.
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "hapfluid/config/scene.hpp"
#include "hapfluid/sim/outputs.hpp"
#include "live_backend.hpp"

namespace {

using namespace hapfluid;

std::string num(double v) { return sim::csv_number(v); }

}  // namespace

int main(int argc, char** argv) {
  std::string out;
  bool quick = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--out" && i + 1 < argc) out = argv[++i];
    else if (a == "--quick") quick = true;
    else {
      std::cerr << "usage: bench_live_backends --out FILE.json [--quick]\n";
      return 2;
    }
  }
  if (out.empty()) {
    std::cerr << "bench_live_backends: --out FILE.json is required\n";
    return 2;
  }
  const std::filesystem::path source = HAPFLUID_SOURCE_DIR;
  // The shipped stirring scene is divergence-free (cpu only); its weakly compressible twin is
  // the same workload for the Vulkan backend.
  const std::vector<std::filesystem::path> scenes = {source / "config/scenes/spoon_stirring.toml",
                                                     source / "tests/sim_gpu_vulkan/scenes/stirring_wcsph.toml",
                                                     source / "tests/sim_gpu_vulkan/scenes/live_stirring_light.toml"};
  struct Run {
    std::string backend;
    int threads;
  };
  const int cores = static_cast<int>(std::max(1L, sysconf(_SC_NPROCESSORS_ONLN)));
  const std::vector<Run> runs = {{"cpu", 1}, {"cpu", cores}, {"vulkan", 0}};
  const double simulated_s = quick ? 0.3 : 1.0, wall_cap_s = quick ? 1.0 : 3.0;
  std::vector<std::string> records;
  for (const auto& path : scenes) {
    config::Scene scene;
    try {
      scene = config::load_scene(path);
    } catch (const std::exception& e) {
      std::cerr << "bench_live_backends: " << path.string() << ": " << e.what() << "\n";
      return 1;
    }
    const sim::SimulationModel model = sim::build_model(scene);
    for (const Run& r : runs) {
      if (r.backend == "cpu" && r.threads == cores && cores == 1) continue;
      sim::LiveBackendOptions options;
      options.threads = std::max(1, r.threads);
      std::unique_ptr<sim::LiveSolver> solver;
      try {
        solver = sim::make_live_solver(model, r.backend, options);
      } catch (const std::exception& e) {
        std::cerr << "bench_live_backends: " << scene.name << " on " << r.backend << ": skipped (" << e.what() << ")\n";
        continue;
      }
      const sim::BackendProbe p = sim::probe_backend(*solver, simulated_s, wall_cap_s);
      const double needed = p.simulated_s > 0 ? double(p.steps) / p.simulated_s : 0;
      std::cerr << "bench_live_backends: " << scene.name << " on " << r.backend << " (" << solver->device().name
                << "): " << num(p.steps_per_s()) << " steps/s, needs " << num(needed) << ", real-time factor "
                << num(p.real_time_factor()) << "\n";
      std::ostringstream j;
      j << "{\"bench\": \"live_backends\", \"params\": {\"scene\": \"" << sim::json_escape(scene.name)
        << "\", \"backend\": \"" << r.backend << "\", \"device\": \"" << sim::json_escape(solver->device().name)
        << "\", \"threads\": " << solver->threads() << ", \"fluid_particles\": " << model.fluid.size()
        << ", \"body_particles\": " << model.body_particles.size() << "}, \"metrics\": {\"steps_per_s\": "
        << num(p.steps_per_s()) << ", \"needed_steps_per_s\": " << num(needed) << ", \"ms_per_step\": "
        << num(p.steps ? 1000.0 * p.wall_s / double(p.steps) : 0) << ", \"real_time_factor\": "
        << num(p.real_time_factor()) << ", \"simulated_s\": " << num(p.simulated_s) << "}}";
      records.push_back(j.str());
    }
  }
  std::ofstream f(out + ".part");
  f << "[\n";
  for (std::size_t i = 0; i < records.size(); ++i) f << "  " << records[i] << (i + 1 < records.size() ? ",\n" : "\n");
  f << "]\n";
  f.close();
  std::filesystem::rename(out + ".part", out);
  return 0;
}
