// Live-mode speed of each backend on the shipped live scenes: what `haptic-sim --live --backend
// auto` decides on (live_backend.hpp), measured the same way (probe_backend: the scene's start,
// devices at their start pose, after warm-up steps) but for longer. A scene runs in real time
// when steps_per_s >= needed_steps_per_s, i.e. real_time_factor >= 1.
//
// Usage: bench_live_backends --out FILE.json [--quick]. Progress on stderr.
#include <unistd.h>

#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "hapfluid/config/command_line.hpp"
#include "hapfluid/config/json_output.hpp"
#include "hapfluid/config/log.hpp"
#include "hapfluid/config/scene.hpp"
#include "hapfluid/sim/outputs.hpp"
#include "live_backend.hpp"

namespace {

using namespace hapfluid;

std::string num(double v) { return sim::csv_number(v); }

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Live-mode speed of each backend on the shipped live scenes; JSON records to --out.",
               "bench_live_backends"};
  config::apply_convention(app);
  std::string out;
  bool quick = false;
  app.add_option("--out", out, "JSON records (a list) to this file")->required();
  app.add_flag("--quick", quick, "shorter probes, for tests");
  if (const int code = config::parse_command_line(app, argc, argv); code >= 0) return code;
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
  std::vector<config::Json> records;
  for (const auto& path : scenes) {
    config::Scene scene;
    try {
      scene = config::load_scene(path);
    } catch (const std::exception& e) {
      log::Line(log::Level::error) << "" << path.string() << ": " << e.what();
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
        log::Line(log::Level::warning) << "" << scene.name << " on " << r.backend << ": skipped (" << e.what() << ")";
        continue;
      }
      const sim::BackendProbe p = sim::probe_backend(*solver, simulated_s, wall_cap_s);
      const double needed = p.simulated_s > 0 ? double(p.steps) / p.simulated_s : 0;
      log::Line(log::Level::info) << "" << scene.name << " on " << r.backend << " (" << solver->device().name
                                  << "): " << num(p.steps_per_s()) << " steps/s, needs " << num(needed) << ", real-time factor "
                                  << num(p.real_time_factor());
      records.push_back(config::bench_record(
          "live_backends",
          {{"scene", scene.name}, {"backend", r.backend}, {"device", solver->device().name},
           {"threads", solver->threads()}, {"fluid_particles", model.fluid.size()},
           {"body_particles", model.body_particles.size()}},
          {{"steps_per_s", p.steps_per_s()}, {"needed_steps_per_s", needed},
           {"ms_per_step", p.steps ? 1000.0 * p.wall_s / double(p.steps) : 0.0},
           {"real_time_factor", p.real_time_factor()}, {"simulated_s", p.simulated_s}}));
    }
  }
  try {
    config::write_json_atomically(out, records);
  } catch (const std::exception& e) {
    log::Line(log::Level::error) << "" << e.what();
    return 1;
  }
  return 0;
}
