// Driver for a 6-DoF haptic arm speaking protocol v1 on any message link (CAN, CAN FD, HID,
// bulk, loopback). poll() drains every pending message and keeps the newest state; send()
// encodes one COMMAND (and a host heartbeat every 100 ms). Neither allocates nor blocks.
#pragma once

#include <memory>
#include <string>

#include "hapfluid/device/device.hpp"
#include "hapfluid/device/message_link.hpp"

namespace hapfluid::device {

class HapticArm final : public Device {
 public:
  // Sends INFO_REQUEST and waits up to `handshake_ms` for INFO (open time, not real time). A
  // device that does not answer is still returned: health().connected stays false until it talks.
  HapticArm(std::string name, std::unique_ptr<MessageLink> link, int handshake_ms = 200);

  bool poll(DeviceState& out) override;
  bool send(const DeviceCommand& command) override;
  DeviceHealth health() const override;
  const char* name() const override { return name_.c_str(); }

  bool has_info() const { return has_info_; }
  const hf_info& info() const { return info_; }
  std::uint32_t device_faults() const { return faults_; }
  MessageLink& link() { return *link_; }

 private:
  void handle(const hf_message& message, std::uint64_t now_ns, bool& updated);
  // STATE sequence check; takes up a device whose counter restarted (health().device_restarts).
  bool accept_state_sequence(std::uint16_t seq);
  // Counts the commands the device's echo skipped (health().commands_lost); `device_ticks`: the
  // device's states since the last one received (1, or more when states were lost). An echo that
  // moved on to one of ours also times that command's round trip (health().echo_round_trip_ns).
  void count_lost_commands(std::uint8_t echo, std::uint32_t device_ticks, std::uint64_t now_ns);
  // This many consecutive "older" states, each one after the other, mean a restarted counter.
  static constexpr std::uint32_t kRestartRun = 3;

  std::string name_;
  std::unique_ptr<MessageLink> link_;
  DeviceState latest_{};
  DeviceHealth health_{};
  hf_seq_tracker state_seq_{};
  std::uint32_t older_run_ = 0;      // consecutive rejected states, each the previous one + 1
  std::uint16_t older_last_ = 0;
  std::uint8_t last_echo_ = 0;
  bool last_echo_ours_ = false;      // last_echo_ names one of our recent commands
  bool echo_seen_ = false;           // an echo arrived since we started or the device restarted
  bool echo_moved_ = false;          // ... and it has changed since: it follows our commands
  std::uint32_t reconnects_seen_ = 0;  // transport reconnections already accounted for
  hf_info info_{};
  bool has_info_ = false;
  std::uint32_t faults_ = 0;
  std::uint16_t command_seq_ = 0;
  std::uint64_t sent_ns_[256] = {};  // when each command went out, by the low 8 bits the echo carries
  std::uint16_t heartbeat_seq_ = 0;
  std::uint16_t estop_seq_ = 0;
  std::uint64_t next_heartbeat_ns_ = 0;
};

std::uint64_t monotonic_ns();

}  // namespace hapfluid::device
