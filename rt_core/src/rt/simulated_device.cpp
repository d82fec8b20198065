#include "hapfluid/rt/simulated_device.hpp"

#include <time.h>

#include <algorithm>
#include <cmath>

#include "hapfluid/safety/wrench.hpp"

namespace hapfluid::rt {
namespace {
std::uint64_t now_ns() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return std::uint64_t(ts.tv_sec) * 1'000'000'000ull + std::uint64_t(ts.tv_nsec);
}
}  // namespace

SimulatedDevice::SimulatedDevice(std::string name, SimulatedHandle handle) : name_(std::move(name)), handle_(handle) {
  for (auto& t : target_) t.store(0.0);
  health_.connected = true;
}

void SimulatedDevice::set_hand_target(double x, double y, double z) {
  target_[0].store(x, std::memory_order_relaxed);
  target_[1].store(y, std::memory_order_relaxed);
  target_[2].store(z, std::memory_order_relaxed);
}

bool SimulatedDevice::poll(device::DeviceState& out) {
  std::uint64_t now = now_ns();
  double dt = last_step_ns_ ? std::min(double(now - last_step_ns_) * 1e-9, 0.01) : 0.0;
  last_step_ns_ = now;
  auto& s = state_;
  for (int i = 0; i < 3; ++i) {
    double target = target_[i].load(std::memory_order_relaxed);
    double f = force_n_[i] - handle_.hand_stiffness_n_per_m * (s.position_m[i] - target) -
               handle_.hand_damping_n_s_per_m * s.linear_velocity_m_s[i];
    s.linear_velocity_m_s[i] += dt * f / handle_.mass_kg;
    s.position_m[i] += dt * s.linear_velocity_m_s[i];
  }
  // Rotation: small-angle restoring torque about the rest orientation.
  safety::Quat q = safety::quat_from(s.orientation);
  safety::V3 angle = safety::rotation_vector(q);
  for (int i = 0; i < 3; ++i) {
    double t = torque_nm_[i] - handle_.hand_angular_stiffness_nm_per_rad * angle[i] -
               handle_.hand_angular_damping_nm_s_per_rad * s.angular_velocity_rad_s[i];
    s.angular_velocity_rad_s[i] += dt * t / handle_.inertia_kg_m2;
  }
  safety::V3 w = safety::from(s.angular_velocity_rad_s);
  safety::Quat dq{1, 0.5 * dt * w.x, 0.5 * dt * w.y, 0.5 * dt * w.z};
  safety::to(safety::normalized(dq * q), s.orientation);

  if (silent_.load(std::memory_order_relaxed)) return false;
  s.host_receive_ns = now;
  s.device_time_us = static_cast<std::uint32_t>(now / 1000);
  ++s.sequence;
  s.buttons = buttons_.load(std::memory_order_relaxed);
  ++health_.frames_ok;
  health_.last_valid_ns = now;
  out = s;
  return true;
}

bool SimulatedDevice::send(const device::DeviceCommand& command) {
  for (int i = 0; i < 3; ++i) {
    force_n_[i] = command.enable && !command.estop ? command.force_n[i] : 0.0;
    torque_nm_[i] = command.enable && !command.estop ? command.torque_nm[i] : 0.0;
  }
  health_.last_command_sequence = static_cast<std::uint16_t>(health_.commands_sent);  // as a wire counter
  ++health_.commands_sent;
  return true;
}

}  // namespace hapfluid::rt
