// The safety layer: every command that reaches a device passes through SafetyLayer::step, once per
// tick, in this fixed order:
//
//   1. non-finite -> zero        NaN/Inf in the command -> zero wrench; a non-finite device state
//                                is a link_invalid fault (step 7).
//   2. passivity controller      adds damping when the observed energy turns active (passivity.hpp).
//   3. magnitude limits          force/torque norm, then per-axis limits; direction preserved.
//   4. sim staleness ramp        no fresh sim sample for sim_stale_ms -> scale ramps 1 -> 0 over
//                                sim_ramp_down_ms; fresh samples again -> ramps back over engage_ramp_ms.
//                                (Ramps use the elapsed time between steps, so skipped ticks do
//                                not stretch them.)
//   5. engage                    after any hard zero, and when a restarted sim's first sample
//                                arrives, the output stays zero until the command of step 3, with fresh sim
//                                samples, is either small (|F| < engage_threshold_n and |tau| <
//                                engage_threshold_nm for engage_small_ms, so the zero crossing of
//                                a ringing spring does not count) or steady: it stayed within the
//                                steady band (engage_steady_band_n/_nm) of one value for engage_hold_ms,
//                                never limited by step 3. A held load (a bucket's weight) is
//                                steady; a large oscillating or drifting command keeps waiting.
//                                Then the output ramps in from zero over max(engage_ramp_ms,
//                                |F| / engage_ramp_rate_n_per_s, |tau| / engage_ramp_rate_nm_per_s),
//                                so the rise is deliberate and step 6 never has to shape it.
//   6. rate limit                change per tick <= max_*_rate * period (uniform scaling, so the
//                                limits of step 3 still hold).
//   7. hard gates                latched e-stop, foreign command or communication-constraint
//                                violation, link timeout/invalid state, device fault, deadman
//                                released (when required) -> exactly zero at once, bypassing the
//                                rate limit: zero is always the safe command.
//   8. passivity observer        accounts for the wrench actually sent.
//
// Recovery rules: e-stop needs reset_estop() while the e-stop input is released, and so does a
// foreign command (someone else commanding our device: whoever it is, the operator must look
// before force returns), and so does a communication-constraint violation (more lost commands
// than max_lost_commands, in a bucket draining that many per lost_command_window_ms); link faults
// clear after link_recover_ms of healthy frames, then the wrench re-engages through step 5;
// sim staleness clears with the first fresh sample and resumes through the step-4 ramp when it is
// the same sim, late (a stall: its bodies and couplings carry on from where the hand left them);
// a restarted sim starts from its own initial state, perhaps far from the hand, so its wrench
// re-engages through step 5 (SafetyInput::sim_restarted).
// The steady window only counts ticks without a hard zero and with fresh sim samples: a command
// computed from a stale device pose says nothing about the load the hand holds now.
// Pure state machine: no clock reads, no I/O, no allocation; time arrives in the input.
#pragma once

#include <cstdint>

#include "hapfluid/safety/flags.hpp"
#include "hapfluid/safety/limits.hpp"
#include "hapfluid/safety/passivity.hpp"
#include "hapfluid/safety/safety_config.hpp"

namespace hapfluid::safety {

struct SafetyInput {
  std::uint64_t now_ns = 0;
  Wrench command;                  // device frame, from the wrench renderer
  V3 linear_velocity_m_s;          // handle twist, device frame
  V3 angular_velocity_rad_s;
  bool fresh_frame = false;        // a new frame arrived this tick
  bool state_valid = true;         // the newest device state is finite and in range
  bool device_fault = false;       // device-reported fault bits, or the transport is disconnected
  bool deadman_pressed = false;
  bool estop_input = false;        // e-stop button / operator request (latches)
  bool foreign_command = false;    // someone else sent this device a command (latches)
  std::uint32_t commands_lost = 0; // commands the device reported not applied since the last step
  bool commands_unheard = false;   // the device's echo has not followed our commands for
                                   // device_watchdog_ms of them while its states keep coming
  double echo_round_trip_ms = -1;  // a command's round trip measured this tick (its echo's first
                                   // state); negative: none
  double sim_age_ms = 1e300;       // time since the newest fresh sim sample arrived; huge: none yet
  bool sim_restarted = false;      // this tick's sample is the first from a new sim (or the first ever)
};

struct SafetyOutput {
  Wrench wrench;                   // the only wrench that may be sent
  bool enable = false;             // false: device must hold zero torque
  bool estop = false;              // latched e-stop
  std::uint32_t flags = 0;
  std::uint32_t faults = 0;
};

class SafetyLayer {
 public:
  explicit SafetyLayer(const SafetyConfig& config) : config_(config), passivity_(config_) {}
  SafetyLayer(const SafetyLayer&) = delete;
  SafetyLayer& operator=(const SafetyLayer&) = delete;

  SafetyOutput step(const SafetyInput& input);
  // Explicit operator reset of a latched e-stop and a latched foreign-command fault; refused
  // (false) while the e-stop input is held.
  bool reset_estop();
  // Operator request: latches the e-stop on the next step.
  void request_estop() { estop_requested_ = true; }

  const SafetyConfig& config() const { return config_; }
  std::uint32_t faults() const { return faults_; }
  double passivity_energy_j() const { return passivity_.energy_j(); }

 private:
  enum class Engage { disengaged, ramping, engaged };
  void update_link(const SafetyInput& in);
  // Step 5's gate while disengaged: true when `command` (after step 3, whose flags are
  // `limit_flags`) may start the engage ramp; sets engage_ramp_ms_ for it.
  bool may_engage(const Wrench& command, std::uint32_t limit_flags, std::uint64_t now_ns);
  void restart_engage_windows() { steady_window_open_ = small_window_open_ = false; }

  SafetyConfig config_;
  PassivityController passivity_;
  Wrench previous_;                // last wrench sent
  std::uint32_t faults_ = fault_link_timeout;  // no frame seen yet
  bool estop_latched_ = false;
  bool estop_requested_ = false;
  bool estop_input_held_ = false;
  bool seen_frame_ = false;
  bool enabled_ = false;  // the last command enabled the motors
  double lost_bucket_ = 0;         // lost commands, draining max_lost_commands per window
  std::uint64_t last_fresh_ns_ = 0;
  std::uint32_t looks_without_frame_ = 0;  // ticks since the last fresh frame
  std::uint64_t slow_echo_since_ns_ = 0;   // first of the round trips beyond link_timeout_ms on end
  std::uint32_t slow_echoes_ = 0;          // how many on end
  std::uint64_t last_now_ns_ = 0;
  std::uint64_t healthy_since_ns_ = 0;
  bool healthy_ = false;
  double stale_scale_ = 0;         // step 4
  Engage engage_ = Engage::disengaged;
  double engage_scale_ = 0;        // step 5
  double engage_ramp_ms_ = 0;      // this engagement's ramp duration
  bool steady_window_open_ = false;
  Wrench steady_reference_;        // the value the command must stay near
  std::uint64_t steady_since_ns_ = 0;
  bool small_window_open_ = false;
  std::uint64_t small_since_ns_ = 0;
};

}  // namespace hapfluid::safety
