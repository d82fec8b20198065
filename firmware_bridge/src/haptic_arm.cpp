// Host-side driver of a protocol-v1 haptic arm.
#include "hapfluid/device/haptic_arm.hpp"

#include <time.h>

#include <cmath>
#include <cstring>

namespace hapfluid::device {

std::uint64_t monotonic_ns() {
  timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::uint64_t>(ts.tv_sec) * 1'000'000'000ull + static_cast<std::uint64_t>(ts.tv_nsec);
}

namespace {
constexpr std::uint64_t kHeartbeatPeriodNs = 100'000'000;  // protocol.md: heartbeats every 100 ms

// A faulted STATE whose fault bits have not arrived (classic CAN carries them only in FAULT
// messages, which may be lost or still queued): the fault holds from this very state. The status
// names the watchdog and the e-stop; any other cause is "internal" until its FAULT message says
// which, so it stays latched rather than being cleared as a watchdog trip.
std::uint32_t faults_from_status(std::uint8_t status) {
  std::uint32_t faults = 0;
  if (status & HF_STATUS_WATCHDOG_TRIPPED) faults |= HF_FAULT_COMMAND_WATCHDOG;
  if (status & HF_STATUS_ESTOP_LATCHED) faults |= HF_FAULT_ESTOP;
  return faults ? faults : HF_FAULT_INTERNAL;
}
}  // namespace

HapticArm::HapticArm(std::string name, std::unique_ptr<MessageLink> link, int handshake_ms)
    : name_(std::move(name)), link_(std::move(link)) {
  health_.echoes_commands = true;
  hf_message request;
  std::memset(&request, 0, sizeof request);
  request.type = HF_MSG_INFO_REQUEST;
  const std::uint64_t deadline = monotonic_ns() + static_cast<std::uint64_t>(handshake_ms) * 1'000'000ull;
  std::uint64_t next_request = 0;
  DeviceState scratch;
  while (!has_info_ && monotonic_ns() < deadline) {
    if (monotonic_ns() >= next_request) {  // requests may be lost: repeat every 20 ms
      link_->send(request);
      ++request.seq;
      next_request = monotonic_ns() + 20'000'000;
    }
    wait_readable(link_->transport(), 5);
    poll(scratch);
  }
}

bool HapticArm::accept_state_sequence(std::uint16_t seq) {
  const std::uint32_t modulus = link_->sequence_modulus();
  if (hf_seq_accept(&state_seq_, seq, modulus)) {
    older_run_ = 0;
    return true;
  }
  // A late or repeated state is one of a kind; states that keep coming "older" and counting up
  // one by one are a device that rebooted and began its counter again. Dropping them until the
  // counter caught up would hold the device at a link fault for up to half a modulus (32 s).
  older_run_ = older_run_ > 0 && seq == (older_last_ + 1) % modulus ? older_run_ + 1 : 1;
  older_last_ = seq;
  if (older_run_ < kRestartRun) return false;
  older_run_ = 0;
  state_seq_.started = 0;  // the new counter is the reference (gaps counted so far are kept)
  hf_seq_accept(&state_seq_, seq, modulus);
  health_.device_restarts++;
  health_.commands_sent_when_heard = health_.commands_sent;  // a rebooted device starts listening anew
  last_echo_ours_ = false;  // its echo starts again too
  echo_seen_ = echo_moved_ = false;
  return true;
}

void HapticArm::count_lost_commands(std::uint8_t echo, std::uint32_t device_ticks, std::uint64_t now_ns) {
  // The echo names the newest command the device applied (low 8 bits). When it moves on by more
  // than the device ticks since the last state we got (states lost on the way are ticks too), the
  // commands between never reached the motors: lost on the link, or superseded in one device
  // tick. Only echoes of our own recent commands count (a device still echoing a previous host's,
  // or one just restarted, says nothing about ours).
  // An echo that has not moved since we started (or since the device restarted) is a previous
  // host's last command, however close its 8 bits fall to ours: a device keeps it until its
  // watchdog lets a new host in, and the jump to our first applied command is not a loss.
  constexpr unsigned kRecent = 64;
  if (!echo_moved_) {
    const bool first = !echo_seen_;
    echo_seen_ = true;
    if (first || echo == last_echo_) {
      last_echo_ = echo;
      last_echo_ours_ = false;
      return;
    }
    echo_moved_ = true;
  }
  const auto newest = static_cast<std::uint8_t>(command_seq_ - 1);
  const bool ours = health_.commands_sent > 0 && static_cast<std::uint8_t>(newest - echo) < kRecent;
  const auto advance = static_cast<std::uint8_t>(echo - last_echo_);
  if (ours && last_echo_ours_ && advance > device_ticks && advance < kRecent)
    health_.commands_lost += advance - device_ticks;
  if (ours && (advance != 0 || !last_echo_ours_)) {
    health_.commands_sent_when_heard = health_.commands_sent;
    // That state left the device after the command reached it, so its age here is at most this
    // round trip. A steady delay on the link shows here, not in the gaps between states.
    const std::uint64_t sent = sent_ns_[echo];
    health_.echo_round_trip_ns = now_ns > sent ? now_ns - sent : 0;
    health_.echo_round_trips++;
  }
  last_echo_ = echo;
  last_echo_ours_ = ours;
}

void HapticArm::handle(const hf_message& m, std::uint64_t now_ns, bool& updated) {
  switch (m.type) {
    case HF_MSG_STATE: {
      const std::uint32_t gaps_before = state_seq_.gaps;
      if (!accept_state_sequence(m.seq)) return;  // late or repeated
      const hf_state& s = m.body.state;
      latest_.host_receive_ns = now_ns;
      latest_.device_time_us = s.device_time_us;
      latest_.sequence = m.seq;
      latest_.command_echo = s.command_echo;
      count_lost_commands(s.command_echo, state_seq_.gaps - gaps_before + 1, now_ns);
      for (int i = 0; i < 3; ++i) {
        latest_.position_m[i] = s.position_m[i];
        latest_.linear_velocity_m_s[i] = s.linear_velocity_m_s[i];
        latest_.angular_velocity_rad_s[i] = s.angular_velocity_rad_s[i];
      }
      for (int i = 0; i < 4; ++i) latest_.orientation[i] = s.orientation[i];
      latest_.buttons = s.buttons;
      latest_.status = s.status;
      // classic CAN has no fault byte in STATE: the FAULT messages keep faults_ current
      if (link_->framing() != Framing::can) faults_ = s.fault;
      if (!(s.status & HF_STATUS_FAULTED)) faults_ = 0;
      else if (!faults_) faults_ = faults_from_status(s.status);
      latest_.fault = faults_;
      health_.frames_ok++;
      health_.last_valid_ns = now_ns;
      health_.connected = true;
      updated = true;
      return;
    }
    case HF_MSG_FAULT:
      faults_ = m.body.fault.faults;
      latest_.fault = faults_;
      health_.frames_ok++;
      return;
    case HF_MSG_DEVICE_HEARTBEAT:
      health_.frames_ok++;
      health_.connected = true;
      return;
    case HF_MSG_INFO:
      info_ = m.body.info;
      has_info_ = true;
      health_.frames_ok++;
      return;
    case HF_MSG_COMMAND:
      // Our own frames never come back to us (SocketCAN without CAN_RAW_RECV_OWN_MSGS, the
      // loopback bus), so a command for our device that we hear was sent by someone else: another
      // process on this machine or another node on the bus, bypassing our safety layer.
      health_.foreign_commands++;
      return;
    default:
      return;  // other host->device messages relayed on a shared bus: not ours to handle
  }
}

bool HapticArm::poll(DeviceState& out) {
  bool updated = false;
  if (const std::uint32_t r = link_->transport().reconnects(); r != reconnects_seen_) {
    // The link came back (a replugged cable, a restarted bus): the device's STATE counter went
    // on, or restarted, meanwhile. Accept its next number as the new reference instead of
    // dropping up to half a modulus of states as "older" (gaps counted so far are kept).
    reconnects_seen_ = r;
    state_seq_.started = 0;
    older_run_ = 0;
    last_echo_ours_ = false;
    echo_seen_ = echo_moved_ = false;
  }
  hf_message m;
  std::uint64_t now = 0;
  int budget = kDrainUnitBudget;
  while (link_->receive(m, budget) == Io::ok) {
    if (!now) now = monotonic_ns();  // one clock read per poll: all frames of a tick arrived together
    handle(m, now, updated);
  }
  if (budget == 0) health_.drains_cut_short++;
  if (updated) out = latest_;
  return updated;
}

bool HapticArm::send(const DeviceCommand& command) {
  hf_message m;
  std::memset(&m, 0, sizeof m);
  m.type = HF_MSG_COMMAND;
  m.seq = command_seq_;
  hf_command& c = m.body.command;
  for (int i = 0; i < 3; ++i) {
    c.force_n[i] = command.force_n[i];
    c.torque_nm[i] = command.torque_nm[i];
  }
  c.flags = static_cast<std::uint8_t>((command.enable ? HF_CMD_ENABLE : 0) | (command.estop ? HF_CMD_ESTOP : 0) |
                                      (command.clear_faults ? HF_CMD_CLEAR_FAULTS : 0));
  const std::uint64_t now = monotonic_ns();
  sent_ns_[command_seq_ & 0xffu] = now;
  bool ok = link_->send(m);
  if (!ok && link_->last_encode_result() != HF_OK) {
    // Not representable (non-finite or beyond full scale): the safety layer failed upstream.
    // Send a disabled zero wrench under this sequence so the motors never keep a stale force.
    std::memset(&c, 0, sizeof c);
    c.flags = command.estop ? HF_CMD_ESTOP : 0;
    link_->send(m);
  }
  if (command.estop) {
    hf_message e;
    std::memset(&e, 0, sizeof e);
    e.type = HF_MSG_ESTOP;
    e.seq = estop_seq_++;
    e.body.estop.reason = 1;  // host safety layer
    link_->send(e);
  }
  health_.last_command_sequence = command_seq_++;
  if (ok) health_.commands_sent++;
  else health_.send_errors++;

  if (now >= next_heartbeat_ns_) {
    hf_message h;
    std::memset(&h, 0, sizeof h);
    h.type = HF_MSG_HOST_HEARTBEAT;
    h.seq = heartbeat_seq_++;
    h.body.heartbeat.uptime_ms = static_cast<std::uint32_t>(now / 1'000'000ull);
    link_->send(h);
    next_heartbeat_ns_ = now + kHeartbeatPeriodNs;
  }
  return ok;
}

DeviceHealth HapticArm::health() const {
  DeviceHealth h = health_;
  h.frames_bad = link_->frames_bad();
  h.sequence_gaps = state_seq_.gaps;
  h.transport_errors = link_->transport().error_flags();
  if (h.transport_errors & (kDisconnected | kBusOff)) h.connected = false;
  return h;
}

}  // namespace hapfluid::device
