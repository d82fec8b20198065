// Named bits the safety layer reports every tick. Flags describe what a stage did to this tick's
// command (informational); faults are causes that force a zero wrench until their recovery rule
// is met. Both are traced per device and per tick, and names print in logs and post-mortems.
#pragma once

#include <cstdint>
#include <string>

namespace hapfluid::safety {

enum Flag : std::uint32_t {
  flag_nonfinite_input = 1u << 0,    // NaN/Inf in the command or the device state: replaced by zero
  flag_force_norm_limited = 1u << 1,
  flag_force_axis_limited = 1u << 2,
  flag_torque_norm_limited = 1u << 3,
  flag_torque_axis_limited = 1u << 4,
  flag_rate_limited = 1u << 5,
  flag_passivity_damping = 1u << 6,  // the passivity controller added damping this tick
  flag_waiting_to_engage = 1u << 7,  // zero output until the command is small enough
  flag_engaging = 1u << 8,           // ramping in
  flag_sim_stale_ramp = 1u << 9,     // sim samples are late: ramping down (or resuming)
  flag_deadman_released = 1u << 10,
  flag_stiffness_capped = 1u << 11,  // coupling-mode K was reduced to the rig's maximum
  flag_hard_zero = 1u << 12,         // a hard gate (fault, e-stop, deadman) zeroed the output
  flag_damping_capped = 1u << 13,    // coupling-mode D was reduced to the rig's maximum
};

enum Fault : std::uint32_t {
  fault_estop = 1u << 0,             // latched; cleared only by an explicit reset
  fault_link_timeout = 1u << 1,      // no valid frame within link_timeout_ms
  fault_link_invalid = 1u << 2,      // the device delivered a non-finite/invalid state
  fault_device_reported = 1u << 3,   // the device's own fault bits are set or it is disconnected
  fault_sim_stale = 1u << 4,         // no fresh sim sample within sim_stale_ms (ramps, not a hard zero)
  fault_foreign_command = 1u << 5,   // a command for this device that we did not send was heard on
                                     // its bus; latched, cleared only by the operator reset
  fault_communication_constraints = 1u << 6,  // too many commands lost (libfranka's
                                     // communication_constraints_violation); latched like the above
  fault_device_not_listening = 1u << 7,  // the device keeps sending states but its command echo has
                                     // not followed our commands for device_watchdog_ms of them: it
                                     // is not hearing us; a link fault, recovers like one
  fault_link_latency = 1u << 8,      // the device's states have echoed our commands later than
                                     // link_timeout_ms after we sent them, link_timeout_ms on end:
                                     // the poses they carry are that old; a link fault, recovers
                                     // like one
};

// "force_norm_limited|rate_limited"; "-" for none.
std::string flag_names(std::uint32_t flags);
std::string fault_names(std::uint32_t faults);

}  // namespace hapfluid::safety
