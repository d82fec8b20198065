// The device firmware of a protocol-v1 haptic arm, emulated: handle dynamics (mass, damping,
// workspace walls, motor force limits), a hand pulling the handle towards a target pose, the
// command watchdog, e-stop latch and fault reporting. Time is passed in, so tests can drive it
// tick by tick; the haptic-fake-device program runs it at 1 kHz on a real link.
#pragma once

#include <cstdint>

#include "hapfluid/config/types.hpp"
#include "hapfluid/wire/codec.h"

namespace hapfluid::fake {

struct DeviceModel {
  double handle_mass_kg = 0.25;
  double handle_damping_n_s_per_m = 2.0;        // the arm's own friction/back-EMF damping
  double handle_inertia_kg_m2 = 1e-3;
  double handle_angular_damping_nm_s_per_rad = 0.01;
  double hand_stiffness_n_per_m = 400.0;        // how firmly the hand holds the handle
  double hand_damping_n_s_per_m = 10.0;
  // A firm wrist (~10 N m/rad, damping ratio ~0.5 with the handle): at 2 N m/rad a pan held by
  // its handle (~0.8 N m) twisted the hand 0.4 rad and laid the pan on the floor.
  double hand_angular_stiffness_nm_per_rad = 10.0;
  double hand_angular_damping_nm_s_per_rad = 0.1;
  double workspace_half_extent_m = 0.30;        // box walls, per axis
  double max_force_n = 12.0;                    // motor limits (norm)
  double max_torque_nm = 0.8;
  // The motors' own rate limits: a change of applied force beyond them per tick is scaled down
  // (direction kept), whoever commanded it; going to zero (motors off, a fault) is never limited.
  double max_force_rate_n_per_s = 2000.0;
  double max_torque_rate_nm_per_s = 100.0;
  int watchdog_ms = 20;                         // no valid command for this long -> motors off
  // A burst of invalid frames from the host (CRC, range, reserved bits: a failing transceiver, a
  // broken gateway, someone else's traffic) means the commands cannot be trusted: this many
  // within bad_command_window_ms latch HF_FAULT_BAD_COMMANDS, motors off.
  int bad_command_burst = 10;
  double bad_command_window_ms = 100.0;
};

// What happened in one tick; the CSV log writes it.
struct TickRecord {
  double t_s = 0;
  bool command_received = false;
  std::uint16_t command_seq = 0;
  hf_command command{};        // the newest command (received this tick or earlier)
  double applied_force_n[3] = {0, 0, 0};    // what the motors pushed on the hand
  double applied_torque_nm[3] = {0, 0, 0};
  double hand_force_n[3] = {0, 0, 0};       // what the hand pushed on the handle
  std::uint8_t status = 0;
  std::uint8_t faults = 0;
};

class FakeFirmware {
 public:
  // sequence_modulus: 256 on classic CAN (8-bit seq on the wire), 65536 elsewhere.
  FakeFirmware(const DeviceModel& model, const config::Pose& start, std::uint32_t sequence_modulus = 65536);

  void begin_tick() { record_.command_received = false; }
  // A message from the host at time `t_s`. Returns true when it asks for an immediate answer
  // (INFO_REQUEST), which the caller sends with info().
  bool receive(const hf_message& message, double t_s);
  // `count` invalid frames from the host arrived at `t_s` (the link counted and skipped them).
  void reject_frames(std::uint32_t count, double t_s);
  // Advances the dynamics by dt towards the hand's target; applies watchdog and limits.
  void step(double t_s, double dt_s, const config::PoseTwist& hand_target);

  hf_state state(std::uint32_t device_time_us) const;
  hf_info info() const;
  hf_fault fault_report(double t_s) const;
  std::uint8_t status() const;
  std::uint8_t faults() const { return faults_; }
  // True once per new fault: the caller sends a FAULT message right away.
  bool take_new_fault() { bool f = new_fault_; new_fault_ = false; return f; }
  const TickRecord& record() const { return record_; }
  // The time the watchdog last tripped and the last valid command before it (-1: never tripped).
  double watchdog_trip_s() const { return watchdog_trip_s_; }
  double watchdog_trip_last_command_s() const { return watchdog_trip_last_command_s_; }
  double last_command_s() const { return last_command_s_; }
  std::uint64_t commands_applied() const { return commands_applied_; }
  std::uint32_t command_sequence_gaps() const { return seq_.gaps; }

 private:
  void raise(std::uint8_t fault_bit, std::uint8_t cause, std::uint32_t detail);

  DeviceModel model_;
  std::uint32_t sequence_modulus_;
  double position_[3];
  double velocity_[3] = {0, 0, 0};
  double orientation_[4];
  double angular_velocity_[3] = {0, 0, 0};
  hf_command command_{};
  std::uint16_t command_seq_ = 0;
  double last_command_s_ = -1;
  double watchdog_trip_s_ = -1;
  double watchdog_trip_last_command_s_ = -1;
  std::uint8_t faults_ = 0;
  std::uint8_t fault_cause_ = 0;
  std::uint32_t fault_detail_ = 0;
  bool new_fault_ = false;
  double bad_window_start_s_ = -1;    // the burst window of reject_frames
  std::uint32_t bad_in_window_ = 0;
  bool saturated_ = false;
  double applied_force_[3] = {0, 0, 0};  // what the motors pushed last tick (the rate limit's start)
  double applied_torque_[3] = {0, 0, 0};
  bool at_wall_ = false;
  bool motors_on_ = false;
  std::uint64_t commands_applied_ = 0;
  hf_seq_tracker seq_{};
  TickRecord record_{};
};

}  // namespace hapfluid::fake
