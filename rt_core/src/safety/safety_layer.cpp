#include "hapfluid/safety/safety_layer.hpp"

#include <algorithm>
#include <cstdint>

namespace hapfluid::safety {
namespace {
constexpr double kNsPerMs = 1e6;
}

void SafetyLayer::update_link(const SafetyInput& in) {
  if (in.fresh_frame && in.state_valid) {
    last_fresh_ns_ = in.now_ns;
    seen_frame_ = true;
    looks_without_frame_ = 0;
  } else if (looks_without_frame_ < UINT32_MAX) {
    ++looks_without_frame_;
  }
  // Silence counts only while the loop was there to hear it: a loop that itself woke late (an
  // overrun, counted as such) first looks for the frames sent meanwhile. Past the device's own
  // watchdog the device has zeroed its motors, so however seldom the loop looked, the link is down.
  const double silent_ms = double(in.now_ns - last_fresh_ns_) / kNsPerMs;
  const double looks_needed = config_.link_timeout_ms / (config_.period_s * 1e3);
  bool timed_out = !seen_frame_ ||
                   (silent_ms > config_.link_timeout_ms && double(looks_without_frame_) > looks_needed) ||
                   silent_ms > std::max(config_.link_timeout_ms, config_.device_watchdog_ms);
  // A steady delay keeps the frames coming at their rate, pose after stale pose. The round trip
  // of our commands bounds how old they are. One slow round trip is a tick the loop or the device
  // woke late (the device applies the newest command it has, so a stall of its own does not
  // lengthen the next one); a whole link timeout of them, every one slow, is the link.
  if (in.echo_round_trip_ms >= 0) {
    if (in.echo_round_trip_ms <= config_.link_timeout_ms) {
      slow_echoes_ = 0;
    } else if (slow_echoes_++ == 0) {
      slow_echo_since_ns_ = in.now_ns;
    }
  }
  const bool late = double(slow_echoes_) >= looks_needed &&
                    double(in.now_ns - slow_echo_since_ns_) >= config_.link_timeout_ms * kNsPerMs;
  bool healthy_now = !timed_out && in.state_valid && !in.device_fault && !in.commands_unheard && !late;
  if (healthy_now && !healthy_) healthy_since_ns_ = in.now_ns;
  healthy_ = healthy_now;

  std::uint32_t link_bits =
      fault_link_timeout | fault_link_invalid | fault_device_reported | fault_device_not_listening | fault_link_latency;
  if (!healthy_now) {
    if (timed_out) faults_ |= fault_link_timeout;
    if (in.commands_unheard) faults_ |= fault_device_not_listening;
    if (late) faults_ |= fault_link_latency;
    if (!in.state_valid) faults_ |= fault_link_invalid;
    if (in.device_fault) faults_ |= fault_device_reported;
  } else if ((faults_ & link_bits) &&
             double(in.now_ns - healthy_since_ns_) >= config_.link_recover_ms * kNsPerMs) {
    faults_ &= ~link_bits;  // healthy long enough; the wrench re-engages through step 5
  }
}

bool SafetyLayer::may_engage(const Wrench& command, std::uint32_t limit_flags, std::uint64_t now_ns) {
  const double force_n = norm(command.force_n), torque_nm = norm(command.torque_nm);
  // Small, and small for engage_small_ms: a ringing spring passes through zero, it does not stay there.
  bool small = force_n < config_.engage_threshold_n && torque_nm < config_.engage_threshold_nm;
  if (!small) {
    small_window_open_ = false;
  } else if (!small_window_open_) {
    small_window_open_ = true;
    small_since_ns_ = now_ns;
  }
  small = small && double(now_ns - small_since_ns_) >= config_.engage_small_ms * kNsPerMs;
  // Steady: within the band of one reference value for the whole hold window. The reference is
  // the first value of the window, so a slow drift leaves the band too (it is not "steady"), and
  // an oscillation wider than the band restarts the window at every excursion.
  // The steady rule judges the command as limited (step 3): a steady load beyond a limit (a pan
  // held by its handle asking more torque than the device has) is rendered at the limit, exactly
  // as it would be had the device stayed engaged; refusing it would leave that hand without any
  // force for the whole run. Only a non-finite command never counts.
  bool steady = false;
  if (config_.engage_hold_ms > 0 && !(limit_flags & flag_nonfinite_input)) {
    bool in_band = steady_window_open_ &&
                   norm(command.force_n - steady_reference_.force_n) <= config_.engage_steady_band_n &&
                   norm(command.torque_nm - steady_reference_.torque_nm) <= config_.engage_steady_band_nm;
    if (!in_band) {
      steady_window_open_ = true;
      steady_reference_ = command;
      steady_since_ns_ = now_ns;
    }
    steady = double(now_ns - steady_since_ns_) >= config_.engage_hold_ms * kNsPerMs;
  } else {
    steady_window_open_ = false;
  }
  if (!small && !steady) return false;
  // Longer for a larger load, so the rise stays at or below engage_ramp_rate (rate limit untouched).
  engage_ramp_ms_ = std::max({config_.engage_ramp_ms, force_n / config_.engage_ramp_rate_n_per_s * 1e3,
                              torque_nm / config_.engage_ramp_rate_nm_per_s * 1e3});
  restart_engage_windows();
  return true;
}

SafetyOutput SafetyLayer::step(const SafetyInput& in) {
  SafetyOutput out;
  // Ramps follow elapsed time, so "zero within sim_ramp_down_ms" holds even when ticks were
  // skipped (overruns); the rate limit stays per tick (the change the device sees at once).
  double dt_ms = config_.period_s * 1e3;
  if (last_now_ns_ != 0 && in.now_ns > last_now_ns_)
    dt_ms = std::min(double(in.now_ns - last_now_ns_) * 1e-6, 100.0);
  last_now_ns_ = in.now_ns;
  V3 v = finite(in.linear_velocity_m_s) ? in.linear_velocity_m_s : V3{};
  V3 w = finite(in.angular_velocity_rad_s) ? in.angular_velocity_rad_s : V3{};
  SafetyInput checked = in;
  if (!finite(in.linear_velocity_m_s) || !finite(in.angular_velocity_rad_s)) {
    checked.state_valid = false;
    out.flags |= flag_nonfinite_input;
  }

  // E-stop latch: a request or a rising e-stop input latches; only reset_estop() clears it.
  estop_input_held_ = in.estop_input;
  if (in.estop_input || estop_requested_) estop_latched_ = true;
  estop_requested_ = false;
  if (estop_latched_) faults_ |= fault_estop;
  if (in.foreign_command) faults_ |= fault_foreign_command;
  // Communication constraint: a link that loses commands now and then (a device tick that took
  // two) is fine; one that loses them in bulk renders a wrench the hand does not get. Commands
  // that kept the motors off lose the hand nothing (a device that caught up after a stall at
  // start-up applies only the newest), so only losses while enabled count.
  lost_bucket_ = std::max(0.0, lost_bucket_ - dt_ms * config_.max_lost_commands / config_.lost_command_window_ms);
  if (enabled_) lost_bucket_ += in.commands_lost;
  if (lost_bucket_ > config_.max_lost_commands) faults_ |= fault_communication_constraints;
  update_link(checked);

  // 1-3: sanitize, passivity, limits.
  Wrench w1 = zero_if_nonfinite(in.command, out.flags);
  Wrench w2 = passivity_.apply(w1, v, w, out.flags);
  Wrench limited = limit_magnitude(w2, config_, out.flags);

  // 4: sim staleness ramp.
  bool stale = in.sim_age_ms > config_.sim_stale_ms;
  if (stale) {
    faults_ |= fault_sim_stale;
    stale_scale_ = std::max(0.0, stale_scale_ - dt_ms / config_.sim_ramp_down_ms);
  } else {
    faults_ &= ~fault_sim_stale;
    // Still engaged (a stall shorter than the ramp-down): fade back in. Disengaged: step 5's ramp
    // from zero is the resume, and this scale must not ramp a second time on top of it.
    stale_scale_ = engage_ == Engage::disengaged ? 1.0 : std::min(1.0, stale_scale_ + dt_ms / config_.engage_ramp_ms);
  }
  if (stale || stale_scale_ < 1.0) out.flags |= flag_sim_stale_ramp;
  Wrench scaled = stale_scale_ * limited;

  // 7 (decided first, applied last): hard gates.
  bool deadman_released = config_.require_deadman && !in.deadman_pressed;
  if (deadman_released) out.flags |= flag_deadman_released;
  bool hard_zero = (faults_ & ~fault_sim_stale) != 0 || deadman_released;

  // 5: engage. A restarted sim's state is new (its body perhaps far from the hand): like after a
  // hard zero, its wrench must pass the gate.
  if (hard_zero || in.sim_restarted) {
    engage_ = Engage::disengaged;
    engage_scale_ = 0;
    restart_engage_windows();
  }
  if (engage_ == Engage::disengaged && !hard_zero) {
    if (!stale && may_engage(limited, out.flags, in.now_ns)) {
      engage_ = Engage::ramping;
    } else {
      out.flags |= flag_waiting_to_engage;
      if (stale) restart_engage_windows();
    }
  }
  if (engage_ == Engage::ramping) {
    engage_scale_ = std::min(1.0, engage_scale_ + dt_ms / engage_ramp_ms_);
    out.flags |= flag_engaging;
    if (engage_scale_ >= 1.0) engage_ = Engage::engaged;
  }
  Wrench engaged = engage_scale_ * scaled;

  // 6: rate limit; 7: hard gates.
  Wrench result = limit_rate(engaged, previous_, config_, out.flags);
  if (hard_zero) {
    result = {};
    out.flags |= flag_hard_zero;
  }

  // 8: observe what is actually sent.
  passivity_.observe(result, v, w);
  previous_ = result;
  out.wrench = result;
  out.enable = !hard_zero;
  enabled_ = out.enable;
  out.estop = estop_latched_;
  out.faults = faults_;
  return out;
}

bool SafetyLayer::reset_estop() {
  if (estop_input_held_) return false;
  estop_latched_ = false;
  faults_ &= ~(fault_estop | fault_foreign_command | fault_communication_constraints);
  lost_bucket_ = 0;
  return true;
}

}  // namespace hapfluid::safety
