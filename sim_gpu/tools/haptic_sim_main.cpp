// haptic-sim: the SPH fluid and rigid-body simulator.
//  - batch: runs a scene with its scripted device motion and writes VTK frames, body/coupling
//    CSV histories and stats.json (batch_run.hpp);
//  - --live: the simulator between haptic-rt and haptic-render over shared memory, its clock
//    the wall clock (sim_gpu/live).
#include <unistd.h>

#include <iostream>
#include <string>
#include <vector>

#include "hapfluid/config/command_line.hpp"
#include "hapfluid/config/errors.hpp"
#include "hapfluid/config/log.hpp"
#include "hapfluid/sim/batch_run.hpp"
#include "hapfluid/sim/command_line_numbers.hpp"
#include "hapfluid/sim/thread_pool.hpp"
#ifdef HAPFLUID_WITH_VULKAN
#include "hapfluid/sim_vulkan/backend.hpp"
#endif
#include "live_runner.hpp"  // sim_gpu/live

namespace {

namespace config = hapfluid::config;
namespace log = hapfluid::log;
namespace sim = hapfluid::sim;

int run_batch_mode(const sim::BatchOptions& o, bool vk_validation, const std::string& vk_device) {
  try {
#ifdef HAPFLUID_WITH_VULKAN
    sim::vulkan::VulkanRunOptions vulkan;
    vulkan.validation = vk_validation;
    vulkan.device = sim::vulkan::parse_device_preference(vk_device);
    const auto r = sim::vulkan::run_batch_on_backend(o, vulkan, std::cerr);
#else
    (void)vk_validation, (void)vk_device;
    const auto r = sim::run_batch(o, std::cerr);
#endif
    log::Line(log::Level::info) << "done: " << r.steps << " steps, " << r.simulated_time_s << " s simulated in " << r.wall_time_s
                                << " s; outputs in " << o.out.string();
    return 0;
  } catch (const config::ConfigError& e) {
    log::Line line(log::Level::error);
    line << "invalid scene:";
    for (const auto& p : e.problems()) line << "\n  " << p.to_string();
    return 1;
  } catch (const std::exception& e) {
    log::Line(log::Level::error) << "error: " << e.what();
    return 1;
  }
}

}  // namespace

int main(int argc, char** argv) {
  const int cores = sim::usable_cpus();
  sim::BatchOptions batch;
  sim::LiveOptions live;
  batch.threads = live.threads = cores;
  bool live_mode = false, vk_validation = false;
  std::string scene, out, backend, vk_device = "auto";
  double duration_s = 0, export_every_s = -1;
  int threads = cores;

  CLI::App app{"The SPH fluid and rigid-body simulator. Batch mode runs a scene with its scripted devices and writes "
               "particles/frame_NNNNNN.vtk (with a .vtk.series), bodies.csv, couplings.csv and stats.json; --live "
               "runs it between haptic-rt and haptic-render over shared memory.",
               "haptic-sim"};
  app.footer(
      "Live mode: device poses come from /<prefix>.device_states (haptic-rt), sim samples go to "
      "/<prefix>.sim_samples and particle frames to /<prefix>.particles (haptic-render); rig device N drives the "
      "scene device with source = \"rig\" and rig_device = \"N\", else the scene device named N "
      "(sim_gpu/live/README.md).");
  config::apply_convention(app);
  auto* live_flag = app.add_flag("--live", live_mode, "run as the live simulator (simulated time follows the wall clock)");
  app.add_option("--scene", scene, "scene file (TOML)")->required();
  app.add_option("--out", out, "output folder (batch: required; live: couplings.csv, bodies.csv, stats.json of the run)");
  app.add_option("--backend", backend,
                 "cpu: the multithreaded reference; vulkan; auto: batch, a GPU, else lavapipe, else cpu with a notice; "
                 "live, Vulkan if a ~1 s probe shows it keeps up with the wall clock, else the faster (default: "
                 "batch cpu, live auto)")
      ->check(CLI::IsMember({"cpu", "vulkan", "auto"}));
  app.add_option("--vk-device", vk_device, "Vulkan device: auto (a GPU, else lavapipe), gpu, cpu (lavapipe)")
      ->check(CLI::IsMember({"auto", "gpu", "cpu", "lavapipe"}))
      ->capture_default_str();
  app.add_option("--duration", duration_s,
                 "batch: simulated seconds (default: the scene's duration_s); live: wall seconds (default 0: until "
                 "SIGINT/SIGTERM)")
      ->check(sim::seconds_from(0, false));
  app.add_option("--threads", threads, "worker threads of the cpu backend (default: one per CPU this process may use)")
      ->check(sim::whole_number_in(1, sim::kMaxWorkerThreads));
  app.add_option("--export-every", export_every_s,
                 "particle frame interval in simulated seconds (batch default 0.05, live default 0: none; 0: none)")
      ->check(sim::seconds_from(0, false));
  app.add_flag("--vk-validation", vk_validation, "batch: run with the Khronos validation layer");
  const std::string live_group = "Live mode (with --live)";
  app.add_option("--rig", live.rig, "take the shm prefix and group from the rig's [rt.shm]")->group(live_group)->needs(live_flag);
  app.add_option("--shm-prefix", live.shm_prefix, "shared-memory prefix (default: the rig's, else \"hapfluid\")")
      ->group(live_group)
      ->needs(live_flag);
  app.add_option("--max-lag", live.max_lag_s, "backlog tolerated before the fluid is declared slower than real time")
      ->check(sim::seconds_from(0.001, false))
      ->capture_default_str()
      ->group(live_group)
      ->needs(live_flag);
  app.add_option("--status-every", live.status_every_s, "status line interval on stderr (0: none)")
      ->check(sim::seconds_from(0, false))
      ->capture_default_str()
      ->group(live_group)
      ->needs(live_flag);
  if (const int code = config::parse_command_line(app, argc, argv); code >= 0) return code;

  if (live_mode) {
    if (vk_validation) {
      log::Line(log::Level::error) << "--vk-validation is a batch-mode option (haptic-sim --help for usage)";
      return config::kUsageExitCode;
    }
    live.scene = scene;
    live.out = out;
    if (!backend.empty()) live.backend = backend;
    live.vulkan_device = vk_device;
    live.duration_s = duration_s;
    live.threads = threads;
    if (export_every_s >= 0) live.export_every_s = export_every_s;
    return sim::run_live(live);
  }
  if (out.empty()) {
    log::Line(log::Level::error) << "--out is required in batch mode (haptic-sim --help for usage)";
    return config::kUsageExitCode;
  }
  if (app.count("--duration") > 0 && duration_s == 0) {
    log::Line(log::Level::error) << "--duration: must be > 0 s in batch mode, not \"0\" (haptic-sim --help for usage)";
    return config::kUsageExitCode;
  }
  batch.scene = scene;
  batch.out = out;
  if (!backend.empty()) batch.backend = backend;
  batch.duration_s = duration_s;
  batch.threads = threads;
  if (export_every_s >= 0) batch.export_every_s = export_every_s;
  batch.progress_line = isatty(STDERR_FILENO);
  return run_batch_mode(batch, vk_validation, vk_device);
}
