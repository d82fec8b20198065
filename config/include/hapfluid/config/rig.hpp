// A rig file describes the physical set-up: which haptic devices exist, how to reach them, the
// limits that keep the hand safe, and how the 1 kHz loop is scheduled. Loaded once at start-up.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "hapfluid/config/types.hpp"

namespace hapfluid::config {

enum class DeviceKind { haptic_arm, spacemouse };
enum class TransportKind { loopback, socketcan, hid, usb_bulk };
// How the 1 kHz loop turns sim samples into a wrench (see rt_core/README.md).
enum class WrenchMode { interpolate, coupling };
// What the loop does when it cannot get SCHED_FIFO / mlockall.
enum class RtPolicy { enforce, ignore };

struct Transport {
  TransportKind kind = TransportKind::loopback;
  // loopback: socket path; socketcan: interface name ("can0"); hid: "vid:pid" or a /dev/hidraw path;
  // usb_bulk: "vid:pid".
  std::string address;
  std::uint32_t can_node_id = 1;  // socketcan and loopback-CAN framing: the device's node id (1..15)
  bool can_fd = false;            // socketcan: one CAN FD frame per message instead of classic frames
  std::string framing = "can";    // loopback: which wire bytes it carries: "can", "canfd", "hid", "bulk"
};

// Device frame -> scene frame: x_scene = offset + scale * R * x_device.
struct WorkspaceMapping {
  Vec3 offset_m;
  double scale = 1.0;
  Quat rotation;
  double force_scale = 1.0;  // scene force -> device force (after safety limits are applied in device units)
};

struct DeviceLimits {
  double max_force_n = 10.0;                    // norm
  double max_torque_nm = 0.5;                   // norm
  Vec3 max_force_axis_n{10.0, 10.0, 10.0};      // per axis, absolute
  Vec3 max_torque_axis_nm{0.5, 0.5, 0.5};
  double max_force_rate_n_per_s = 1000.0;       // change of force per second
  double max_torque_rate_nm_per_s = 50.0;
  double max_stiffness_n_per_m = 2000.0;        // caps the coupling-mode K rendered at 1 kHz
  double max_angular_stiffness_nm_per_rad = 5.0;
  double max_coupling_damping_n_s_per_m = 20.0; // caps the coupling-mode D rendered at 1 kHz
  double max_coupling_angular_damping_nm_s_per_rad = 0.2;
  double device_damping_n_s_per_m = 2.0;        // physical damping of the arm (passivity bound)
};

struct Watchdogs {
  double sim_stale_ms = 50.0;        // no fresh sim sample for this long -> ramp the wrench down
  double sim_ramp_down_ms = 100.0;   // ... to zero over this long
  double link_timeout_ms = 5.0;      // no valid frame from the device for this long -> link fault
  double link_recover_ms = 100.0;    // a faulted link must be healthy this long before forces return
  double engage_threshold_n = 1.0;   // forces engage only once the commanded force is below this
  double engage_threshold_nm = 0.0;  // ... and the torque below this; 0: threshold_n * max_torque / max_force
  double engage_ramp_ms = 200.0;     // then ramp in over this long
  double engage_small_ms = 50.0;     // "below": for this long (a ringing spring only crosses zero); 0: at once
  // Engaging under a resting load (a held bucket's weight never drops below the threshold): a
  // command that stayed within +/- engage_steady_band_n (and _nm) for engage_hold_ms, within the
  // limits, engages too. 0 ms: off. 0 for the _nm band/rate: derived like engage_threshold_nm.
  double engage_hold_ms = 150.0;
  double engage_steady_band_n = 0.5;
  double engage_steady_band_nm = 0.0;
  // The ramp from zero never rises faster than this: it lasts max(engage_ramp_ms, |F| / rate).
  double engage_ramp_rate_n_per_s = 20.0;
  double engage_ramp_rate_nm_per_s = 0.0;
  double device_watchdog_ms = 20.0;  // device firmware: no valid command for this long -> motors off
  // Communication constraint: more than max_lost_commands commands the device never applied
  // (lost, or superseded in one of its ticks), counted in a leaky bucket that drains
  // max_lost_commands per lost_command_window_ms, latch a fault until the operator's reset.
  double lost_command_window_ms = 100.0;
  double max_lost_commands = 50.0;
};

// Time-domain passivity observer/controller (Hannaford & Ryu 2002) in the 1 kHz loop.
struct Passivity {
  bool enabled = true;
  double max_damping_n_s_per_m = 20.0;        // most damping the controller may add
  double max_damping_nm_s_per_rad = 0.2;
  double energy_cap_j = 0.2;                  // the observer's stored-energy reservoir
};

struct RigDevice {
  std::string name;
  DeviceKind kind = DeviceKind::haptic_arm;
  Transport transport;
  WorkspaceMapping mapping;
  DeviceLimits limits;
  Watchdogs watchdogs;
  Passivity passivity;
  WrenchMode wrench_mode = WrenchMode::interpolate;
  bool require_deadman = false;  // forces only while the enable/deadman button is held
};

struct SharedMemory {
  std::string prefix = "hapfluid";  // segments are /<prefix>.<channel>
  std::string group;                // owning group of the segments (mode 0660); empty: process group
};

struct RtSettings {
  std::int64_t period_ns = 1'000'000;
  int priority = 80;               // SCHED_FIFO priority 1..99
  int cpu = -1;                    // CPU to pin the loop to; -1: no pinning
  // Where in each period the loop wakes, from whole multiples of period_ns on CLOCK_MONOTONIC.
  // Not 0: the kernel's scheduler tick fires on those multiples (all CPUs), and a wake-up that
  // coincides with it waits behind the tick's work (docs/rig-setup.md). Default period_ns / 4.
  std::int64_t wake_phase_ns = 250'000;
  RtPolicy policy = RtPolicy::ignore;
  SharedMemory shm;
  std::uint32_t trace_ring_records = 65536;  // power of two
  std::uint32_t flight_recorder_ticks = 500;
};

// haptic-dashboard, the operator's read-only page: where it listens. Loopback by default; reach
// it from another machine through an SSH tunnel (docs/rig-setup.md).
struct DashboardSettings {
  std::string address = "127.0.0.1:8642";  // HOST:PORT
};

struct Rig {
  std::filesystem::path file;
  std::string name;
  RtSettings rt;
  DashboardSettings dashboard;
  std::vector<RigDevice> devices;

  const RigDevice* find_device(const std::string& name) const;
};

// Throws ConfigError listing every problem in the file.
Rig load_rig(const std::filesystem::path& file);
Rig parse_rig(const std::string& toml_text, const std::filesystem::path& file_for_messages);

const char* to_string(DeviceKind);
const char* to_string(TransportKind);
const char* to_string(WrenchMode);
const char* to_string(RtPolicy);

}  // namespace hapfluid::config
