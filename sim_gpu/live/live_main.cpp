#include "live_main.hpp"

#include <unistd.h>

#include <cstring>
#include <iostream>
#include <string>

#include "hapfluid/sim/command_line_numbers.hpp"
#include "hapfluid/sim/thread_pool.hpp"
#include "live_runner.hpp"

namespace hapfluid::sim {
namespace {

void usage(std::ostream& out) {
  out << "usage: haptic-sim --live --scene FILE [--rig FILE] [--shm-prefix NAME] [--out DIR] [--duration S]\n"
         "                  [--threads N] [--backend auto|vulkan|cpu] [--vk-device auto|gpu|cpu] [--max-lag S]\n"
         "                  [--status-every S] [--export-every S]\n"
         "  --live              run as the live simulator: device poses from /<prefix>.device_states\n"
         "                      (haptic-rt), sim samples to /<prefix>.sim_samples, particle frames to\n"
         "                      /<prefix>.particles (haptic-render); simulated time follows the wall clock\n"
         "  --rig FILE          take the shm prefix and group from the rig's [rt.shm]\n"
         "  --shm-prefix NAME   shared-memory prefix (default: the rig's, else \"hapfluid\")\n"
         "  --out DIR           write couplings.csv, bodies.csv and stats.json of the live run\n"
         "  --export-every S    particle frames DIR/particles/frame_NNNNNN.vtk every S simulated seconds, as\n"
         "                      batch mode (at most the scene's frame rate; default 0: none; needs --out)\n"
         "  --duration S        stop after S seconds of wall time (default: until SIGINT/SIGTERM)\n"
         "  --threads N         worker threads of the cpu backend (default: all cores)\n"
         "  --backend B         auto (default): Vulkan (a GPU, else lavapipe) if a ~1 s probe at start shows it keeps\n"
         "                      up with the wall clock on this scene, else the faster of Vulkan and cpu, said\n"
         "                      loudly; cpu when no Vulkan device is usable (with a notice). vulkan|cpu: that one\n"
         "  --vk-device D       Vulkan device: auto (a GPU, else lavapipe), gpu, cpu (lavapipe)\n"
         "  --max-lag S         backlog tolerated before the fluid is declared slower than real time (0.1)\n"
         "  --status-every S    status line interval on stderr (default 5; 0: none)\n"
         "Rig device N drives the scene device with source = \"rig\" and rig_device = \"N\", else the\n"
         "scene device named N (sim_gpu/live/README.md).\n";
}

}  // namespace

bool wants_live(int argc, char** argv) {
  for (int i = 1; i < argc; ++i)
    if (std::strcmp(argv[i], "--live") == 0) return true;
  return false;
}

int live_main(int argc, char** argv) {
  LiveOptions o;
  o.threads = static_cast<int>(std::max(1L, sysconf(_SC_NPROCESSORS_ONLN)));
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--live") continue;
    if (a == "-h" || a == "--help") return usage(std::cout), 0;
    if (i + 1 >= argc) {
      std::cerr << "haptic-sim: " << a << " needs a value\n";
      return usage(std::cerr), 2;
    }
    const char* v = argv[++i];
    if (a == "--scene") o.scene = v;
    else if (a == "--rig") o.rig = v;
    else if (a == "--shm-prefix") o.shm_prefix = v;
    else if (a == "--out") o.out = v;
    else if (a == "--backend") o.backend = v;
    else if (a == "--vk-device") o.vulkan_device = v;
    else if (a == "--duration") {
      if (!accepted(std::cerr, a, v, parse_seconds(v, 0, false, o.duration_s))) return 2;
    } else if (a == "--threads") {
      if (!accepted(std::cerr, a, v, parse_whole_number(v, 1, kMaxWorkerThreads, o.threads))) return 2;
    } else if (a == "--max-lag") {
      if (!accepted(std::cerr, a, v, parse_seconds(v, 0.001, false, o.max_lag_s))) return 2;
    } else if (a == "--export-every") {
      if (!accepted(std::cerr, a, v, parse_seconds(v, 0, false, o.export_every_s))) return 2;
    } else if (a == "--status-every") {
      if (!accepted(std::cerr, a, v, parse_seconds(v, 0, false, o.status_every_s))) return 2;
    } else {
      std::cerr << "haptic-sim: unknown option " << a << " (live mode)\n";
      return usage(std::cerr), 2;
    }
  }
  if (o.scene.empty()) {
    std::cerr << "haptic-sim: --live needs --scene FILE\n";
    return usage(std::cerr), 2;
  }
  return run_live(o, std::cerr);
}

}  // namespace hapfluid::sim
