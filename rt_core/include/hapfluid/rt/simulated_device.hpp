// SimulatedDevice: an in-process stand-in for a haptic arm, used when haptic-rt runs with
// --simulated-devices (CI, laptops, the multi-process tests) until the firmware_bridge drivers
// and their loopback transport are merged. It is NOT a driver and never talks to hardware.
//
// Model: a handle of mass m held by a soft "hand" (a spring-damper to its rest pose) and pushed by
// the commanded force; orientation follows the commanded torque through a rotational
// inertia-damper. Integrated with semi-implicit Euler at every poll(). Frames are always fresh
// and valid unless a test silences it (set_silent) or injects a fault.
#pragma once

#include <atomic>
#include <cstdint>
#include <string>

#include "hapfluid/device/device.hpp"

namespace hapfluid::rt {

struct SimulatedHandle {
  double mass_kg = 0.3;
  double hand_stiffness_n_per_m = 200.0;
  double hand_damping_n_s_per_m = 8.0;
  double inertia_kg_m2 = 1e-3;
  double hand_angular_stiffness_nm_per_rad = 1.0;
  double hand_angular_damping_nm_s_per_rad = 0.05;
};

class SimulatedDevice final : public device::Device {
 public:
  explicit SimulatedDevice(std::string name, SimulatedHandle handle = {});
  bool poll(device::DeviceState& out) override;
  bool send(const device::DeviceCommand& command) override;
  device::DeviceHealth health() const override { return health_; }
  const char* name() const override { return name_.c_str(); }

  // Fault injection for tests (thread-safe: set from a non-RT thread).
  void set_silent(bool silent) { silent_.store(silent, std::memory_order_relaxed); }
  void set_buttons(std::uint32_t buttons) { buttons_.store(buttons, std::memory_order_relaxed); }
  // Hand target: where the simulated hand pulls the handle (test-driven motion).
  void set_hand_target(double x, double y, double z);

 private:
  std::string name_;
  SimulatedHandle handle_;
  device::DeviceState state_;
  device::DeviceHealth health_;
  double force_n_[3] = {0, 0, 0};
  double torque_nm_[3] = {0, 0, 0};
  std::atomic<double> target_[3];
  std::uint64_t last_step_ns_ = 0;
  std::atomic<bool> silent_{false};
  std::atomic<std::uint32_t> buttons_{1};  // deadman held
};

}  // namespace hapfluid::rt
