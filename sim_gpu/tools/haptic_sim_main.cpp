// haptic-sim: the SPH fluid and rigid-body simulator. Batch mode runs a scene with its scripted
// device motion and writes VTK frames, body/coupling CSV histories and stats.json.
//   haptic-sim --scene FILE --backend cpu --duration SECONDS --out DIR [--threads N] [--export-every SECONDS]
#include <unistd.h>

#include <iostream>
#include <string>

#include "hapfluid/config/errors.hpp"
#include "hapfluid/sim/batch_run.hpp"
#include "hapfluid/sim/command_line_numbers.hpp"
#include "hapfluid/sim/thread_pool.hpp"
#ifdef HAPFLUID_WITH_VULKAN
#include "hapfluid/sim_vulkan/backend.hpp"
#endif
#include "live_main.hpp"  // sim_gpu/live: haptic-sim --live

namespace {

void usage(std::ostream& out) {
  out << "usage: haptic-sim --scene FILE --out DIR [--backend cpu|auto] [--duration SECONDS] [--threads N]\n"
         "                  [--export-every SECONDS]\n"
         "  --scene FILE          scene file (TOML)\n"
         "  --out DIR             output folder: particles/frame_NNNNNN.vtk, bodies.csv, couplings.csv, stats.json\n"
         "  --backend cpu|auto    simulation backend (cpu: the multithreaded reference; auto: best available)\n"
         "  --duration SECONDS    simulated time (default: the scene's duration_s)\n"
         "  --threads N           worker threads (default: all cores)\n"
         "  --export-every SECONDS  particle frame interval (default 0.05; 0: no particle frames)\n"
#ifdef HAPFLUID_WITH_VULKAN
         "  --backend vulkan|auto  Vulkan compute (auto: a GPU, else lavapipe, else cpu with a notice)\n"
         "  --vk-device auto|gpu|cpu  which Vulkan device (cpu: lavapipe)\n"
         "  --vk-validation       run with the Khronos validation layer\n"
#endif
      ;
}

}  // namespace

int main(int argc, char** argv) {
  namespace sim = hapfluid::sim;
  if (sim::wants_live(argc, argv)) return sim::live_main(argc, argv);
  sim::BatchOptions o;
#ifdef HAPFLUID_WITH_VULKAN
  sim::vulkan::VulkanRunOptions vulkan;
#endif
  o.threads = static_cast<int>(std::max(1L, sysconf(_SC_NPROCESSORS_ONLN)));
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "-h" || a == "--help") {
      usage(std::cout);
      return 0;
    }
#ifdef HAPFLUID_WITH_VULKAN
    if (a == "--vk-validation") {
      vulkan.validation = true;
      continue;
    }
#endif
    if (i + 1 >= argc) {
      std::cerr << "haptic-sim: " << a << " needs a value\n";
      usage(std::cerr);
      return 2;
    }
    const char* v = argv[++i];
    if (a == "--scene") o.scene = v;
    else if (a == "--out") o.out = v;
    else if (a == "--backend") o.backend = v;
#ifdef HAPFLUID_WITH_VULKAN
    else if (a == "--vk-device") {
      try {
        vulkan.device = sim::vulkan::parse_device_preference(v);
      } catch (const std::exception& e) {
        return std::cerr << "haptic-sim: --vk-device: " << e.what() << "\n", 2;
      }
    }
#endif
    else if (a == "--duration") {
      if (!sim::accepted(std::cerr, a, v, sim::parse_seconds(v, 0, true, o.duration_s))) return 2;
    } else if (a == "--threads") {
      if (!sim::accepted(std::cerr, a, v, sim::parse_whole_number(v, 1, sim::kMaxWorkerThreads, o.threads))) return 2;
    } else if (a == "--export-every") {
      if (!sim::accepted(std::cerr, a, v, sim::parse_seconds(v, 0, false, o.export_every_s))) return 2;
    } else {
      std::cerr << "haptic-sim: unknown option " << a << "\n";
      usage(std::cerr);
      return 2;
    }
  }
  if (o.scene.empty() || o.out.empty()) {
    std::cerr << "haptic-sim: --scene and --out are required\n";
    usage(std::cerr);
    return 2;
  }
  o.progress_line = isatty(STDERR_FILENO);
  try {
#ifdef HAPFLUID_WITH_VULKAN
    const auto r = sim::vulkan::run_batch_on_backend(o, vulkan, std::cerr);
#else
    const auto r = sim::run_batch(o, std::cerr);
#endif
    std::cerr << "haptic-sim: done: " << r.steps << " steps, " << r.simulated_time_s << " s simulated in " << r.wall_time_s
              << " s; outputs in " << o.out.string() << "\n";
    return 0;
  } catch (const hapfluid::config::ConfigError& e) {
    std::cerr << "haptic-sim: invalid scene:\n";
    for (const auto& p : e.problems()) std::cerr << "  " << p.to_string() << "\n";
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "haptic-sim: error: " << e.what() << "\n";
    return 1;
  }
}
