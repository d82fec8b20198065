#include "hapfluid/rt/loop.hpp"

#include <time.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>

#include "hapfluid/wire/codec.h"

namespace hapfluid::rt {
namespace {

std::uint64_t now_ns() { return shm::monotonic_ns(); }

std::uint32_t next_power_of_two(std::uint32_t n) {
  std::uint32_t p = 1;
  while (p < n) p <<= 1;
  return p;
}

bool state_valid(const device::DeviceState& s) {
  for (int i = 0; i < 3; ++i)
    if (!std::isfinite(s.position_m[i]) || !std::isfinite(s.linear_velocity_m_s[i]) ||
        !std::isfinite(s.angular_velocity_rad_s[i]))
      return false;
  double q2 = 0;
  for (double c : s.orientation) q2 += c * c;
  return std::isfinite(q2) && q2 > 0.81 && q2 < 1.21;  // |q| within 10% of a unit quaternion
}

Twist6 device_twist(const device::DeviceState& s) {
  return {safety::from(s.position_m), safety::normalized(safety::quat_from(s.orientation)),
          safety::from(s.linear_velocity_m_s), safety::from(s.angular_velocity_rad_s)};
}

}  // namespace

RtLoop::PerDevice::PerDevice(const config::RigDevice& d, std::int64_t period_ns)
    : workspace(d.mapping),
      safety(safety::make_safety_config(d, period_ns)),
      interpolator(16'666'667, std::uint64_t(period_ns)),
      mode(d.wrench_mode),
      caps{d.limits.max_stiffness_n_per_m / workspace.linear_gain(),
           d.limits.max_angular_stiffness_nm_per_rad / workspace.angular_gain(),
           d.limits.max_coupling_damping_n_s_per_m / workspace.linear_gain(),
           d.limits.max_coupling_angular_damping_nm_s_per_rad / workspace.angular_gain()} {}

RtLoop::RtLoop(const config::Rig& rig, std::vector<std::unique_ptr<device::Device>> devices, LoopOptions options)
    : rig_(rig) {
  if (devices.size() != rig.devices.size() || devices.size() > std::size_t(shm::kMaxDevices))
    throw std::runtime_error("haptic-rt: " + std::to_string(devices.size()) + " devices for a rig with " +
                             std::to_string(rig.devices.size()) + " (at most " + std::to_string(shm::kMaxDevices) + ")");
  for (std::size_t i = 0; i < devices.size(); ++i) {
    devices_.push_back(std::make_unique<PerDevice>(rig.devices[i], rig.rt.period_ns));
    devices_.back()->device = std::move(devices[i]);
    // Counts from before the loop are not this run's (a foreign command heard at open is: it
    // still latches on the first tick).
    const device::DeviceHealth health = devices_.back()->device->health();
    devices_.back()->device_restarts = health.device_restarts;
    devices_.back()->commands_lost = health.commands_lost;
    devices_.back()->echo_round_trips = health.echo_round_trips;
    auto& entry = states_record_.devices[i];
    std::strncpy(entry.name, rig.devices[i].name.c_str(), sizeof entry.name - 1);
    entry.present = 1;
  }
  states_record_.device_count = static_cast<std::uint32_t>(devices_.size());
  const std::string prefix = options.shm_prefix.empty() ? rig.rt.shm.prefix : options.shm_prefix;
  shm::WriterOptions writer_options{rig.rt.shm.group, 0640};
  device_states_ = shm::LatestWriter::create(shm::segment_name(prefix, shm::ChannelKind::device_states),
                                             shm::ChannelKind::device_states, sizeof(shm::DeviceStatesRecord), 4,
                                             writer_options);
  if (options.publish_trace)
    trace_ = shm::RingWriter::create(shm::segment_name(prefix, shm::ChannelKind::trace), shm::ChannelKind::trace,
                                     sizeof(shm::TraceRecord), rig.rt.trace_ring_records, writer_options);
  // Twice the dump window, so the ticks before a fault survive until the supervisor copies them.
  flight_recorder_ = shm::RingWriter::create_private(shm::ChannelKind::flight_recorder, sizeof(shm::TraceRecord),
                                                     next_power_of_two(2 * rig.rt.flight_recorder_ticks + 64));
}

RtLoop::~RtLoop() {
  // Leave the devices with a zero, disabled command, then remove our segments.
  for (auto& d : devices_) {
    device::DeviceCommand zero{};
    if (d->device) d->device->send(zero);
  }
  device_states_.close();
  trace_.close();
}

void RtLoop::read_sim(std::uint64_t now, std::uint32_t& loop_flags) {
  // Adopt a mapping the supervisor offers; acknowledging its epoch lets it free the old one.
  if (SimAttachment* offered = sim_offer_.load(std::memory_order_acquire); offered != sim_) {
    sim_ = offered;
    sim_epoch_ack_.store(sim_ ? sim_->epoch : 0, std::memory_order_release);
  }
  // A corrupt segment (header rewritten, object shrunk) is no sim at all: no new samples, so the
  // safety layer ages the last one out exactly as for a sim that died.
  if (!sim_ || !sim_->reader.valid() || !sim_->reader.segment().intact()) {
    loop_flags |= loop_sim_not_attached;
    return;
  }
  // Nothing new since the last copy: skip the 2-3 KB read.
  std::uint64_t incarnation = sim_->reader.segment().layout().incarnation;
  if (incarnation == sample_incarnation_ && sim_->reader.published() == sample_generation_) return;
  std::uint64_t generation = 0;
  shm::ReadResult r = sim_->reader.try_read(scratch_, &generation);
  if (r == shm::ReadResult::busy) loop_flags |= loop_sim_read_busy;
  if (r != shm::ReadResult::ok) return;
  bool restarted = incarnation != sample_incarnation_;
  if (!restarted && generation == sample_generation_) return;
  if (restarted)
    for (auto& d : devices_) {
      d->interpolator.reset();
      d->sim_restarted = true;
    }
  track_sim_pace(scratch_, restarted || !have_sample_);
  sample_ = scratch_;
  sample_generation_ = generation;
  sample_incarnation_ = incarnation;
  last_new_sample_ns_ = now;
  have_sample_ = true;
  loop_flags |= loop_new_sim_sample;
}

void RtLoop::track_sim_pace(const shm::SimSample& next, bool first) {
  // Simulated seconds per wall second of the sample stream: the simulated time between
  // consecutive samples (sim_time_s) against the wall time between them (publish_ns), each
  // averaged over ~4 samples before they are divided, so a burst of samples after a stall
  // weighs no more than the stall, then clamped to [0, 1]. A sim slower than real time moves its
  // bodies by their velocities in simulated time only: the anchor may move on at that pace,
  // never faster. Until two samples are known: 0, a fixed anchor.
  if (first) {
    pace_sim_s_ = pace_wall_s_ = sim_pace_ = 0.0;
    return;
  }
  const double sim_s = next.sim_time_s - sample_.sim_time_s;
  const double wall_s = double(std::int64_t(next.publish_ns - sample_.publish_ns)) * 1e-9;
  if (!std::isfinite(sim_s) || !(wall_s >= 0)) return;  // a sample from a broken clock says nothing
  pace_sim_s_ = 0.75 * pace_sim_s_ + 0.25 * std::clamp(sim_s, 0.0, 1.0);
  pace_wall_s_ = 0.75 * pace_wall_s_ + 0.25 * std::min(wall_s, 1.0);
  sim_pace_ = pace_wall_s_ > 0 ? std::clamp(pace_sim_s_ / pace_wall_s_, 0.0, 1.0) : 0.0;
}

double RtLoop::sim_age_ms(std::uint64_t now) const {
  if (!have_sample_) return 1e300;
  // The older of "since it arrived here" and "since the sim published it" (same CLOCK_MONOTONIC):
  // a sample left in the segment of a crashed sim is stale on arrival, and a sample stamped in
  // the future by a broken sim still ages by its arrival time.
  std::uint64_t since_arrival = now - last_new_sample_ns_;
  std::uint64_t since_publish = sample_.publish_ns <= now ? now - sample_.publish_ns : 0;
  return double(since_arrival > since_publish ? since_arrival : since_publish) * 1e-6;
}

double RtLoop::pose_age_s(const shm::SimSample& s, double cap_s) const {
  // The couplings' pose x0 against this tick's device pose, both by when they were polled: since
  // device_tick's poll, less the lead the sim moved that pose on by (so negative right after the
  // poll), at most cap_s. A tick from the future or none (0): no age. One older than the ring
  // remembers, or from a loop before a restart (its time unknown): the cap. A lead that is no
  // number, negative or beyond the cap: none.
  if (s.device_tick == 0 || s.device_tick > current_tick_) return 0.0;
  const double lead = std::isfinite(s.pose_lead_s) && s.pose_lead_s >= 0 && s.pose_lead_s <= cap_s ? s.pose_lead_s : 0.0;
  if (current_tick_ - s.device_tick >= kPollTimes) return cap_s;
  const std::uint64_t then = poll_ns_[s.device_tick % kPollTimes], polled = poll_ns_[current_tick_ % kPollTimes];
  if (then == 0 || then > polled) return cap_s;
  return std::min(double(polled - then) * 1e-9 - lead, cap_s);
}

void RtLoop::render_device(PerDevice& d, std::size_t index, std::uint64_t now, bool new_sample) {
  bool valid = state_valid(d.state);
  Twist6 scene = d.workspace.to_scene(valid ? device_twist(d.state) : Twist6{});
  const shm::CouplingModel& model = sample_.couplings[index];
  bool coupled = have_sample_ && index < sample_.device_count && model.valid == 1;
  std::uint32_t capped = 0;  // flag_stiffness_capped, flag_damping_capped
  safety::Wrench scene_command{};
  if (d.mode == config::WrenchMode::interpolate) {
    if (new_sample) d.interpolator.on_sample(coupled ? safety::Wrench{safety::from(model.force_n), safety::from(model.torque_nm)}
                                                     : safety::Wrench{},
                                             now);
    scene_command = d.interpolator.render(now);
  } else if (coupled) {
    // Past the staleness limit the safety layer ramps the wrench out; the anchor stops there too.
    const double cap_s = d.safety.config().sim_stale_ms * 1e-3;
    scene_command = render_coupling(model, scene, d.caps, sim_pace_ * pose_age_s(sample_, cap_s), capped);
  }

  device::DeviceHealth health = d.device->health();
  // A device that rebooted lost whatever it had applied; its new stream is taken up like after
  // any link loss: this state counts as invalid, and link recovery and the engage gate decide
  // when the wrench returns.
  const bool restarted = health.device_restarts != d.device_restarts;
  d.device_restarts = health.device_restarts;
  const bool foreign = health.foreign_commands != d.foreign_commands;
  d.foreign_commands = health.foreign_commands;
  const auto lost = static_cast<std::uint32_t>(health.commands_lost - d.commands_lost);
  d.commands_lost = health.commands_lost;
  // A device that keeps talking but takes none of our commands (its echo stands still) would
  // leave the loop engaged while the motors do whatever the device last heard. Counted in
  // commands, not time: a loop that stalled sent none meanwhile, and a device that stalled
  // echoes the newest in its first state after. The allowance is the device's own watchdog.
  const double unheard = double(health.commands_sent - health.commands_sent_when_heard);
  const bool unheard_long = unheard * d.safety.config().period_s * 1e3 > d.safety.config().device_watchdog_ms;
  safety::SafetyInput in;
  in.now_ns = now;
  in.command = d.workspace.to_device(scene_command);
  in.linear_velocity_m_s = safety::from(d.state.linear_velocity_m_s);
  in.angular_velocity_rad_s = safety::from(d.state.angular_velocity_rad_s);
  in.fresh_frame = d.fresh;
  in.state_valid = valid && !restarted;
  in.device_fault = d.state.fault != 0 || !health.connected;
  in.deadman_pressed = (d.state.buttons & 1u) != 0;
  in.estop_input = (d.state.buttons & 2u) != 0;  // bit 1: e-stop button on the device
  in.foreign_command = foreign;
  in.commands_lost = lost;
  in.commands_unheard = health.echoes_commands && d.fresh && unheard_long;
  if (health.echo_round_trips != d.echo_round_trips) {
    d.echo_round_trips = health.echo_round_trips;
    in.echo_round_trip_ms = double(health.echo_round_trip_ns) * 1e-6;
    LinkQuality& q = d.link;
    ++q.round_trips;
    q.round_trip_ms = in.echo_round_trip_ms;
    q.longest_round_trip_ms = std::max(q.longest_round_trip_ms, in.echo_round_trip_ms);
  }
  in.sim_age_ms = sim_age_ms(now);
  in.sim_restarted = d.sim_restarted;
  d.sim_restarted = false;
  safety::SafetyOutput out = d.safety.step(in);
  out.flags |= capped;

  safety::to(out.wrench.force_n, d.command.force_n);
  safety::to(out.wrench.torque_nm, d.command.torque_nm);
  d.command.enable = out.enable;
  d.command.estop = out.estop;
  // A latched command-watchdog trip, and nothing else, is the device's answer to our own silence
  // (a link loss longer than device_watchdog_ms, a stalled loop). Once its frames flow again we
  // clear it, which the device honours only while disabled, so clearing never switches force on:
  // the safety layer's link recovery and engage gate decide when the wrench returns.
  // Every other device fault (e-stop, over-current, workspace, bad commands) stays latched.
  d.command.clear_faults = !out.enable && !out.estop && d.fresh && valid && d.state.fault == HF_FAULT_COMMAND_WATCHDOG;
  d.scene_wrench = d.workspace.to_scene(out.wrench);

  auto& entry = states_record_.devices[index];
  entry.buttons = d.state.buttons;
  entry.safety_flags = out.flags;
  entry.faults = out.faults;
  entry.host_receive_ns = d.state.host_receive_ns;
  safety::to(scene.position_m, entry.position_m);
  safety::to(scene.orientation, entry.orientation);
  safety::to(scene.linear_velocity_m_s, entry.linear_velocity_m_s);
  safety::to(scene.angular_velocity_rad_s, entry.angular_velocity_rad_s);
  safety::to(d.scene_wrench.force_n, entry.force_n);
  safety::to(d.scene_wrench.torque_nm, entry.torque_nm);

  auto& t = last_trace_.devices[index];
  t.safety_flags = out.flags;
  t.faults = out.faults;
  for (int i = 0; i < 3; ++i) {
    t.force_n[i] = static_cast<float>(d.command.force_n[i]);
    t.torque_nm[i] = static_cast<float>(d.command.torque_nm[i]);
  }
  t.link_miss_run = d.link.miss_run;
  t.fresh = d.fresh ? 1 : 0;
  t.state_sequence = d.state.sequence;
  t.state_receive_ns = d.state.host_receive_ns;
}

void RtLoop::tick(std::uint64_t scheduled_ns, std::uint64_t wake_ns) {
  // Budget: the whole tick (device I/O included) must fit well inside rt.period_ns (1 ms);
  // the compute part targets p99.9 <= 20 us with two devices. Nothing here may allocate or block.
  std::uint64_t tick = tick_count_.load(std::memory_order_relaxed) + 1;
  std::uint32_t loop_flags = degraded_flags_ | overrun_flag_;
  overrun_flag_ = 0;

  if (estop_request_.exchange(false, std::memory_order_relaxed))
    for (auto& d : devices_) d->safety.request_estop();
  if (estop_reset_request_.exchange(false, std::memory_order_relaxed))
    for (auto& d : devices_) d->safety.reset_estop();

  std::uint64_t io_start = now_ns();
  current_tick_ = tick;
  poll_ns_[tick % kPollTimes] = io_start;
  for (auto& d : devices_) {
    d->fresh = d->device->poll(d->state);
    LinkQuality& q = d->link;
    ++q.ticks;
    if (d->fresh) {
      ++q.fresh_ticks;
      q.miss_run = 0;
    } else if (++q.miss_run > q.longest_miss_run) {
      q.longest_miss_run = q.miss_run;
    }
  }
  std::uint64_t io_ns = now_ns() - io_start;

  std::uint64_t now = now_ns();
  read_sim(now, loop_flags);
  bool new_sample = loop_flags & loop_new_sim_sample;
  std::uint32_t faults = 0;
  for (std::size_t i = 0; i < devices_.size(); ++i) {
    render_device(*devices_[i], i, now, new_sample);
    faults |= last_trace_.devices[i].faults;
  }

  std::uint64_t send_start = now_ns();
  for (auto& d : devices_) d->device->send(d->command);
  std::uint64_t send_end = now_ns();
  for (std::size_t i = 0; i < devices_.size(); ++i)
    last_trace_.devices[i].command_sequence = devices_[i]->device->health().last_command_sequence;
  io_ns += send_end - send_start;

  publish(tick, scheduled_ns);

  // A fault cause that was not there last tick: ask the supervisor for a flight-recorder dump.
  if (std::uint32_t rising = faults & ~previous_faults_; rising && tick > 1) {
    fault_bits_.store(rising, std::memory_order_relaxed);
    std::uint64_t expected = 0;
    fault_tick_.compare_exchange_strong(expected, tick, std::memory_order_acq_rel);
  }
  previous_faults_ = faults;

  auto& t = last_trace_;
  t.tick = tick;
  t.scheduled_ns = scheduled_ns;
  t.wake_ns = wake_ns;
  t.sim_age_ns = have_sample_ ? std::int64_t(now) - std::int64_t(sample_.publish_ns) : -1;
  t.sim_device_tick = have_sample_ ? sample_.device_tick : 0;
  t.sim_publish_ns = have_sample_ ? sample_.publish_ns : 0;
  t.send_ns = send_start;
  t.io_ns = static_cast<std::uint32_t>(io_ns);
  t.compute_ns = static_cast<std::uint32_t>(now_ns() - wake_ns - io_ns);
  t.loop_flags = loop_flags;
  t.overruns = static_cast<std::uint32_t>(overruns_.load(std::memory_order_relaxed));
  t.device_count = static_cast<std::uint32_t>(devices_.size());
  if (trace_.valid()) trace_.push(t);
  flight_recorder_.push(t);
  tick_count_.store(tick, std::memory_order_release);
}

void RtLoop::publish(std::uint64_t tick, std::uint64_t scheduled_ns) {
  states_record_.tick = tick;
  states_record_.time_ns = scheduled_ns;
  device_states_.publish(states_record_);
}

void RtLoop::run(std::uint64_t duration_ns) {
  const std::uint64_t period = static_cast<std::uint64_t>(rig_.rt.period_ns);
  std::uint64_t start = now_ns();
  // On the period grid, shifted by rt.wake_phase_ns off the kernel's scheduler tick (which fires on
  // whole multiples of its own period, and so of 1 ms): the two coinciding doubles the median wake
  // latency (docs/rig-setup.md, "Wake latency").
  const std::uint64_t phase = static_cast<std::uint64_t>(rig_.rt.wake_phase_ns);
  std::uint64_t next = (start / period + 1) * period + phase;
  std::uint64_t end = duration_ns ? start + duration_ns : ~0ull;
  while (running_.load(std::memory_order_relaxed) && next < end) {
    timespec ts{static_cast<time_t>(next / 1'000'000'000ull), static_cast<long>(next % 1'000'000'000ull)};
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
    }
    std::uint64_t wake = now_ns();
    tick(next, wake);
    next += period;
    // Re-phase: if the next slot has already passed, skip the missed slots (counted) rather than
    // running them back to back, which would burst stale commands at the device.
    std::uint64_t after = now_ns();
    if (after >= next) {
      std::uint64_t missed = (after - next) / period + 1;
      next += missed * period;
      overruns_.fetch_add(missed, std::memory_order_relaxed);
      overrun_flag_ = loop_overrun;
    }
  }
}

}  // namespace hapfluid::rt
