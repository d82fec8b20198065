// Every number the safety layer uses, in one struct, built from the rig file (whose own defaults
// are safe); describe() prints all of them at start-up, so no limit is ever silent.
#pragma once

#include <string>

#include "hapfluid/config/rig.hpp"
#include "hapfluid/safety/wrench.hpp"

namespace hapfluid::safety {

struct SafetyConfig {
  double period_s = 0.001;
  // Limits (device frame, device units), from the rig's device limits.
  double max_force_n = 10.0;
  double max_torque_nm = 0.5;
  V3 max_force_axis_n{10, 10, 10};
  V3 max_torque_axis_nm{0.5, 0.5, 0.5};
  double max_force_rate_n_per_s = 1000.0;
  double max_torque_rate_nm_per_s = 50.0;
  // Watchdogs, from the rig's device watchdogs.
  double sim_stale_ms = 50.0;
  double sim_ramp_down_ms = 100.0;
  double link_timeout_ms = 5.0;
  double device_watchdog_ms = 20.0;  // the device zeroes its motors after this long without commands
  double engage_threshold_n = 1.0;
  double engage_ramp_ms = 200.0;
  bool require_deadman = false;
  double engage_threshold_nm = 0.05;             // torque counterpart of engage_threshold_n
  // Engaging under a resting load: a command that stayed within +/- the steady band for
  // engage_hold_ms (judged after the limits: a load beyond them engages at the limit) may engage
  // too; 0 ms turns this rule off. The ramp from zero then lasts max(engage_ramp_ms, |F| / engage_ramp_rate_n_per_s, |tau| / ..._nm_per_s).
  double engage_hold_ms = 150.0;
  double engage_small_ms = 50.0;  // a small command must stay small this long (0: at once)
  double engage_steady_band_n = 0.5;
  double engage_steady_band_nm = 0.025;
  double engage_ramp_rate_n_per_s = 20.0;
  double engage_ramp_rate_nm_per_s = 1.0;
  double link_recover_ms = 100.0;                // healthy link this long before the link fault clears
  double lost_command_window_ms = 100.0;         // communication constraint (rig.hpp, Watchdogs)
  double max_lost_commands = 50.0;
  double passivity_max_damping_n_s_per_m = 20.0; // most damping the passivity controller may add
  double passivity_max_damping_nm_s_per_rad = 0.2;
  double passivity_energy_cap_j = 0.2;           // the observer's stored-energy reservoir cap
  bool passivity_enabled = true;
};

SafetyConfig make_safety_config(const config::RigDevice& device, std::int64_t period_ns);
// Multi-line, one "name = value (source)" per line, for the start-up log.
std::string describe(const SafetyConfig& config);

}  // namespace hapfluid::safety
