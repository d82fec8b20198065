// Live mode of haptic-sim: the simulator as a service between haptic-rt and
// haptic-render, over the hapfluid_shm channels (rt_core/include/hapfluid/shm/layouts.hpp).
//
//   device_states (haptic-rt -> sim)   device poses, scene frame
//   sim_samples   (sim -> haptic-rt)   body states and one CouplingModel per device (F0/tau0 at
//                                      x0/q0 plus K/D), published after every step
//   particles     (sim -> haptic-render) fluid particles and body transforms at the scene's
//                                      frame rate
//
// Device matching rule (documented in sim_gpu/live/README.md): device_states entry i carries a
// rig device name N. It drives the scene device whose `source = "rig"` and `rig_device = N`;
// failing that, the scene device NAMED N (a scripted scene device played by haptic-fake-device,
// whose rig device has the scene device's name). Its coupling is published in
// sim_samples.couplings[i]. Scene devices no rig device drives keep their script (source =
// scripted, evaluated at simulated time) or hold their start pose (source = rig).
//
// Time: simulated time follows CLOCK_MONOTONIC. The sim steps (CFL-limited substeps) whenever
// the wall clock has reached the simulated time, so it leads the wall by at most one step. When
// the steps take longer than the time they simulate, the backlog beyond `max_lag_s` is dropped
// (the fluid runs slower than real time): that is said once on stderr and the real-time factor
// is in every status line and in stats.json.
#pragma once

#include <filesystem>
#include <string>

namespace hapfluid::sim {

struct LiveOptions {
  std::filesystem::path scene;
  std::filesystem::path rig;       // optional: shm prefix and group from the rig's [rt.shm]
  std::string backend = "auto";    // cpu | vulkan | auto (live_backend.hpp has the rule)
  std::string vulkan_device = "auto";  // auto | gpu | cpu (lavapipe)
  std::string shm_prefix;          // empty: the rig's, else "hapfluid"
  std::filesystem::path out;       // empty: no files (couplings.csv, bodies.csv, stats.json)
  double export_every_s = 0;       // VTK particle frames in out/particles/ every S simulated seconds; 0: none
  double duration_s = 0;           // wall seconds; 0: until SIGINT/SIGTERM
  int threads = 1;
  double max_lag_s = 0.1;          // backlog tolerated before the fluid is declared slower than real time
  double status_every_s = 5;       // status line on stderr (0: none)
};

// Runs until SIGINT/SIGTERM (handlers installed here) or the duration. Returns the process exit
// code: 0 clean stop, 1 simulation error (non-finite state), 2 bad options/scene/shm.
int run_live(const LiveOptions& options);

}  // namespace hapfluid::sim
