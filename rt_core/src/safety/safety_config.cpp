#include "hapfluid/safety/safety_config.hpp"

#include <cstdio>

#include "hapfluid/safety/flags.hpp"

namespace hapfluid::safety {

SafetyConfig make_safety_config(const config::RigDevice& d, std::int64_t period_ns) {
  SafetyConfig c;
  c.period_s = double(period_ns) * 1e-9;
  const auto& l = d.limits;
  c.max_force_n = l.max_force_n;
  c.max_torque_nm = l.max_torque_nm;
  c.max_force_axis_n = {l.max_force_axis_n.x, l.max_force_axis_n.y, l.max_force_axis_n.z};
  c.max_torque_axis_nm = {l.max_torque_axis_nm.x, l.max_torque_axis_nm.y, l.max_torque_axis_nm.z};
  c.max_force_rate_n_per_s = l.max_force_rate_n_per_s;
  c.max_torque_rate_nm_per_s = l.max_torque_rate_nm_per_s;
  const auto& w = d.watchdogs;
  c.sim_stale_ms = w.sim_stale_ms;
  c.sim_ramp_down_ms = w.sim_ramp_down_ms;
  c.link_timeout_ms = w.link_timeout_ms;
  c.device_watchdog_ms = w.device_watchdog_ms;
  c.engage_threshold_n = w.engage_threshold_n;
  c.engage_ramp_ms = w.engage_ramp_ms;
  c.require_deadman = d.require_deadman;
  // Unless given, the torque engage threshold is in proportion to the force one, relative to the limits.
  c.engage_threshold_nm = w.engage_threshold_nm > 0 ? w.engage_threshold_nm
                                                    : w.engage_threshold_n * l.max_torque_nm / l.max_force_n;
  c.link_recover_ms = w.link_recover_ms;
  c.lost_command_window_ms = w.lost_command_window_ms;
  c.max_lost_commands = w.max_lost_commands;
  c.engage_hold_ms = w.engage_hold_ms;
  c.engage_small_ms = w.engage_small_ms;
  c.engage_steady_band_n = w.engage_steady_band_n;
  c.engage_ramp_rate_n_per_s = w.engage_ramp_rate_n_per_s;
  // The torque counterparts, unless given, scale with the limits like engage_threshold_nm.
  double torque_per_force = l.max_torque_nm / l.max_force_n;
  c.engage_steady_band_nm = w.engage_steady_band_nm > 0 ? w.engage_steady_band_nm
                                                        : w.engage_steady_band_n * torque_per_force;
  c.engage_ramp_rate_nm_per_s = w.engage_ramp_rate_nm_per_s > 0 ? w.engage_ramp_rate_nm_per_s
                                                                : w.engage_ramp_rate_n_per_s * torque_per_force;
  c.passivity_enabled = d.passivity.enabled;
  c.passivity_max_damping_n_s_per_m = d.passivity.max_damping_n_s_per_m;
  c.passivity_max_damping_nm_s_per_rad = d.passivity.max_damping_nm_s_per_rad;
  c.passivity_energy_cap_j = d.passivity.energy_cap_j;
  return c;
}

std::string describe(const SafetyConfig& c) {
  char text[2048];
  std::snprintf(
      text, sizeof text,
      "  max_force_n = %g (rig)\n  max_torque_nm = %g (rig)\n"
      "  max_force_axis_n = [%g, %g, %g] (rig)\n  max_torque_axis_nm = [%g, %g, %g] (rig)\n"
      "  max_force_rate_n_per_s = %g (rig)\n  max_torque_rate_nm_per_s = %g (rig)\n"
      "  sim_stale_ms = %g, sim_ramp_down_ms = %g (rig)\n  link_timeout_ms = %g, device_watchdog_ms = %g (rig)\n"
      "  engage_threshold_n = %g, engage_ramp_ms = %g (rig)\n  require_deadman = %s (rig)\n"
      "  engage_threshold_nm = %g (rig, or engage_threshold_n * max_torque_nm / max_force_n)\n"
      "  link_recover_ms = %g (rig)\n"
      "  max_lost_commands = %g per lost_command_window_ms = %g (rig)\n"
      "  engage_small_ms = %g (rig)\n"
      "  engage_hold_ms = %g, engage_steady_band_n = %g, engage_steady_band_nm = %g (rig; 0 ms: only small commands engage)\n"
      "  engage_ramp_rate_n_per_s = %g, engage_ramp_rate_nm_per_s = %g (rig)\n"
      "  passivity: %s, max damping %g N*s/m and %g N*m*s/rad, energy cap %g J (rig)\n",
      c.max_force_n, c.max_torque_nm, c.max_force_axis_n.x, c.max_force_axis_n.y, c.max_force_axis_n.z,
      c.max_torque_axis_nm.x, c.max_torque_axis_nm.y, c.max_torque_axis_nm.z, c.max_force_rate_n_per_s,
      c.max_torque_rate_nm_per_s, c.sim_stale_ms, c.sim_ramp_down_ms, c.link_timeout_ms, c.device_watchdog_ms, c.engage_threshold_n,
      c.engage_ramp_ms, c.require_deadman ? "true" : "false", c.engage_threshold_nm, c.link_recover_ms,
      c.max_lost_commands, c.lost_command_window_ms,
      c.engage_small_ms, c.engage_hold_ms, c.engage_steady_band_n, c.engage_steady_band_nm, c.engage_ramp_rate_n_per_s,
      c.engage_ramp_rate_nm_per_s,
      c.passivity_enabled ? "on" : "off", c.passivity_max_damping_n_s_per_m, c.passivity_max_damping_nm_s_per_rad,
      c.passivity_energy_cap_j);
  return text;
}

namespace {
std::string names(std::uint32_t bits, const char* const* table, int count) {
  if (!bits) return "-";
  std::string s;
  for (int i = 0; i < count; ++i)
    if (bits & (1u << i)) {
      if (!s.empty()) s += '|';
      s += table[i];
    }
  return s;
}
}  // namespace

std::string flag_names(std::uint32_t flags) {
  static const char* const table[] = {"nonfinite_input",  "force_norm_limited", "force_axis_limited",
                                      "torque_norm_limited", "torque_axis_limited", "rate_limited",
                                      "passivity_damping", "waiting_to_engage",  "engaging",
                                      "sim_stale_ramp",     "deadman_released",   "stiffness_capped",
                                      "hard_zero",          "damping_capped"};
  return names(flags, table, 14);
}

std::string fault_names(std::uint32_t faults) {
  static const char* const table[] = {"estop",     "link_timeout", "link_invalid", "device_reported",
                                      "sim_stale", "foreign_command", "communication_constraints_violation",
                                      "device_not_listening", "link_latency"};
  return names(faults, table, 9);
}

}  // namespace hapfluid::safety
