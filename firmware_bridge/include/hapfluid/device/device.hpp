// The one small interface the 1 kHz loop uses to talk to any device, whatever the transport
// (CAN, USB HID, USB bulk, loopback) or kind (haptic arm, SpaceMouse). Real-time rules: after
// open(), no call here allocates, locks or blocks beyond the transport's non-blocking I/O.
#pragma once

#include <cstdint>

namespace hapfluid::device {

// Units: m, m/s, rad/s, N, N·m; orientation is a unit quaternion (w, x, y, z); device frame.
struct DeviceState {
  std::uint64_t host_receive_ns = 0;  // CLOCK_MONOTONIC when the newest frame arrived
  std::uint32_t device_time_us = 0;   // the device's own clock, wraps
  std::uint16_t sequence = 0;
  std::uint16_t command_echo = 0;     // sequence (low 8 bits) of the newest command the device applied
  double position_m[3] = {0, 0, 0};
  double orientation[4] = {1, 0, 0, 0};
  double linear_velocity_m_s[3] = {0, 0, 0};
  double angular_velocity_rad_s[3] = {0, 0, 0};
  std::uint32_t buttons = 0;          // bit 0: deadman/enable
  std::uint32_t status = 0;           // device status bits (protocol.md)
  std::uint32_t fault = 0;            // device-reported fault bits; 0 = healthy
};

struct DeviceCommand {
  double force_n[3] = {0, 0, 0};
  double torque_nm[3] = {0, 0, 0};
  bool enable = false;                // false: the device must hold zero motor torque
  bool estop = false;                 // latched emergency stop request
  bool clear_faults = false;          // explicit recovery: clears latched device faults, only
                                      // honoured together with enable = false
};

struct DeviceHealth {
  std::uint64_t frames_ok = 0;        // valid frames received
  std::uint64_t frames_bad = 0;       // CRC, length, version or range errors
  std::uint64_t sequence_gaps = 0;    // frames lost between valid ones
  std::uint64_t commands_sent = 0;
  std::uint16_t last_command_sequence = 0;  // sequence number the newest command went out with
  std::uint64_t send_errors = 0;
  std::uint64_t last_valid_ns = 0;    // CLOCK_MONOTONIC of the newest valid frame
  std::uint32_t transport_errors = 0; // bit set: bus-off, error-passive, disconnected, ...
  std::uint64_t drains_cut_short = 0; // polls that stopped at the drain bound (a frame flood)
  std::uint32_t device_restarts = 0;  // the device's state counter began again (it rebooted)
  std::uint64_t foreign_commands = 0; // COMMANDs for this device heard on its bus that we did not send
  std::uint64_t commands_lost = 0;    // our commands the device never applied (its echo skipped them)
  // Devices whose states echo the newest command they applied: commands_sent at the newest state
  // whose echo moved on to one of ours (reset to commands_sent when the device restarts), so
  // commands_sent - commands_sent_when_heard is how many the device has not been seen to take.
  bool echoes_commands = false;
  std::uint64_t commands_sent_when_heard = 0;
  // From the send of the command that the newest echo moved on to, to the state that carried the
  // echo (the host's clock, at its poll). echo_round_trips counts the measurements.
  std::uint64_t echo_round_trip_ns = 0;
  std::uint64_t echo_round_trips = 0;
  bool connected = false;
};

class Device {
 public:
  virtual ~Device() = default;
  // Drains whatever arrived without blocking; true when `out` was updated with a newer state.
  virtual bool poll(DeviceState& out) = 0;
  // Queues or sends one command without blocking; false when it could not be sent.
  virtual bool send(const DeviceCommand& command) = 0;
  virtual DeviceHealth health() const = 0;
  virtual const char* name() const = 0;
};

}  // namespace hapfluid::device
