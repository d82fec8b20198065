// Which backend the live sim runs on (`haptic-sim --live --backend cpu|vulkan|auto`).
//
//   cpu     the multithreaded CPU reference.
//   vulkan  the Vulkan backend on the device --vk-device picks (a GPU, else lavapipe); fails
//           with the cause and the fix when no Vulkan device can run the scene.
//   auto    (the default) Vulkan on any usable device (GPU or lavapipe) IF it keeps up with the
//           wall clock on this scene, else the faster backend, said loudly:
//             1. a scene the Vulkan backend does not run yet (dfsph with dynamic bodies), or
//                no usable Vulkan device -> cpu, with a one-line notice saying why;
//             2. a probe: the scene's first ~0.3 s (at most 0.6 s of wall time) stepped on a
//                throw-away Vulkan solver, devices at their start pose. Real-time factor
//                >= 1.1 (10% headroom for publishing and the other processes) -> vulkan;
//             3. otherwise the same probe on the cpu backend, and the backend with the higher
//                real-time factor runs, with a NOTICE giving both numbers.
//           The live run starts at simulated time 0 on a fresh solver either way, and still
//           reports its real-time factor and says when it cannot keep up (live_runner.hpp).
//
// Why a probe: on a 2-core machine lavapipe steps a weakly compressible stirring scene (~850
// fluid particles, ~1250 steps per simulated second) at ~400-600 steps/s while the cpu backend on
// one thread makes ~1500 (sim_gpu/live/README.md has the numbers); on a rig with a GPU, Vulkan wins.
// The rule is "Vulkan by default, never a silently slowed fluid": the probe decides
// which on the machine and scene at hand instead of a hard-coded device list.
#pragma once

#include <memory>
#include <stdexcept>
#include <string>

#include "hapfluid/config/scene.hpp"
#include "live_solver.hpp"

namespace hapfluid::sim {

struct LiveBackendOptions {
  std::string backend = "auto";     // cpu | vulkan | auto
  std::string vulkan_device = "auto";  // --vk-device auto | gpu | cpu (lavapipe)
  int threads = 1;                  // cpu backend worker threads
  // auto: Vulkan runs when its probe's real-time factor is at least this.
  double vulkan_min_real_time_factor = 1.1;
  double probe_simulated_s = 0.3;   // per backend probed; whichever limit comes first
  double probe_wall_s = 0.6;
};

// One backend's probe: steps of the scene's start timed on a throw-away solver.
struct BackendProbe {
  bool ran = false;
  std::uint64_t steps = 0;
  double simulated_s = 0, wall_s = 0;
  double steps_per_s() const { return wall_s > 0 ? double(steps) / wall_s : 0; }
  double real_time_factor() const { return wall_s > 0 ? simulated_s / wall_s : 0; }
};

struct LiveBackend {
  std::unique_ptr<LiveSolver> solver;
  std::string requested;   // what --backend asked for
  std::string reason;      // why this backend runs (one sentence; start line and stats.json)
  BackendProbe vulkan_probe, cpu_probe;
};

// A --backend that cannot run as asked (unknown name, `vulkan` without a usable device): the
// message names the cause and the fix.
class BackendUnavailable : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The solver of one backend, "cpu" or "vulkan" (no choice, no probe); throws what the backend's
// constructor throws (vulkan::VulkanUnavailable without a usable device).
std::unique_ptr<LiveSolver> make_live_solver(const SimulationModel& model, const std::string& backend,
                                             const LiveBackendOptions& options);

// Builds the model of `scene` and the solver chosen by the rule above. Notices go to the log.
// Throws BackendUnavailable, or std::runtime_error for a scene no backend can run.
LiveBackend choose_live_backend(const config::Scene& scene, const LiveBackendOptions& options);

// Steps `solver` (devices as set) for up to `simulated_s` of simulated time or `wall_s` of wall
// time, after a few untimed warm-up steps (first submissions, caches).
BackendProbe probe_backend(LiveSolver& solver, double simulated_s, double wall_s);

}  // namespace hapfluid::sim
