// SpaceMouse driver: 3Dconnexion HID reports -> integrated 6-DoF pose (rate control).
#include "hapfluid/device/spacemouse.hpp"

#include <cmath>
#include <cstring>

#include "hapfluid/device/haptic_arm.hpp"

namespace hapfluid::device {

namespace {
double i16(const std::uint8_t* p) { return static_cast<std::int16_t>(p[0] | (p[1] << 8)); }
double clamp(double v, double limit) { return v > limit ? limit : v < -limit ? -limit : v; }
}  // namespace

SpaceMouse::SpaceMouse(std::string name, std::unique_ptr<Transport> transport, SpaceMouseScaling scaling)
    : name_(std::move(name)), transport_(std::move(transport)), scaling_(scaling) {}

bool SpaceMouse::apply_report(const WireFrame& r) {
  if (r.length < 1) return false;
  switch (r.data[0]) {
    case 1:
      if (r.length < 7) return false;
      for (int i = 0; i < 3; ++i) translation_raw_[i] = i16(r.data + 1 + 2 * i);
      if (r.length >= 13)  // newer models: rotation in the same report
        for (int i = 0; i < 3; ++i) rotation_raw_[i] = i16(r.data + 7 + 2 * i);
      return true;
    case 2:
      if (r.length < 7) return false;
      for (int i = 0; i < 3; ++i) rotation_raw_[i] = i16(r.data + 1 + 2 * i);
      return true;
    case 3: {
      std::uint32_t buttons = 0;
      for (int i = 1; i < r.length && i <= 4; ++i) buttons |= static_cast<std::uint32_t>(r.data[i]) << (8 * (i - 1));
      state_.buttons = buttons;
      return true;
    }
    default:
      return false;  // other reports (LEDs, battery) carry no motion
  }
}

void SpaceMouse::integrate(double dt_s) {
  const double k = 1.0 / scaling_.full_deflection;
  double w[3];
  for (int i = 0; i < 3; ++i) {
    double v = clamp(translation_raw_[i] * k, 1.0) * scaling_.max_speed_m_s;
    double p = state_.position_m[i] + v * dt_s;
    double limited = clamp(p, scaling_.workspace_half_extent_m);
    state_.position_m[i] = limited;
    state_.linear_velocity_m_s[i] = limited == p ? v : 0.0;  // at the workspace wall the pose stops
    w[i] = clamp(rotation_raw_[i] * k, 1.0) * scaling_.max_rate_rad_s;
    state_.angular_velocity_rad_s[i] = w[i];
  }
  // q' = 0.5 * (0, w) x q with w in the world frame, then renormalise
  double* q = state_.orientation;
  double dq[4] = {-w[0] * q[1] - w[1] * q[2] - w[2] * q[3], w[0] * q[0] + w[1] * q[3] - w[2] * q[2],
                  w[1] * q[0] + w[2] * q[1] - w[0] * q[3], w[2] * q[0] + w[0] * q[2] - w[1] * q[1]};
  double n = 0;
  for (int i = 0; i < 4; ++i) {
    q[i] += 0.5 * dq[i] * dt_s;
    n += q[i] * q[i];
  }
  n = std::sqrt(n);
  for (int i = 0; i < 4; ++i) q[i] /= n;
}

bool SpaceMouse::poll(DeviceState& out) {
  const std::uint64_t now = monotonic_ns();
  bool got = false;
  WireFrame report;
  for (int budget = kDrainUnitBudget; budget > 0 && transport_->receive(report) == Io::ok; --budget) {
    if (apply_report(report)) {
      health_.frames_ok++;
      health_.last_valid_ns = now;
      health_.connected = true;
      got = true;
    } else {
      health_.frames_bad++;
    }
  }
  double dt = last_integration_ns_ ? (now - last_integration_ns_) * 1e-9 : 0.0;
  last_integration_ns_ = now;
  bool moving = false;
  for (int i = 0; i < 3; ++i) moving = moving || translation_raw_[i] != 0 || rotation_raw_[i] != 0;
  integrate(dt > 0.05 ? 0.05 : dt);  // a stalled caller must not teleport the pose
  state_.host_receive_ns = got ? now : state_.host_receive_ns;
  if (got || moving) {
    state_.sequence++;
    out = state_;
  }
  return got || moving;
}

bool SpaceMouse::send(const DeviceCommand& command) {
  for (int i = 0; i < 3; ++i)
    if (command.force_n[i] != 0 || command.torque_nm[i] != 0) return false;
  return true;
}

DeviceHealth SpaceMouse::health() const {
  DeviceHealth h = health_;
  h.transport_errors = transport_->error_flags();
  if (h.transport_errors & kDisconnected) h.connected = false;
  return h;
}

}  // namespace hapfluid::device
