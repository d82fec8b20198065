// Emulated device firmware: the same rules a real arm's microcontroller would apply.
#include "fake_firmware.hpp"

#include <cmath>
#include <cstring>

namespace hapfluid::fake {

namespace {

// Scales v so its norm is at most limit (direction preserved); returns true if it scaled.
bool limit_norm(double v[3], double limit) {
  double n = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  if (n <= limit || n == 0) return false;
  for (int i = 0; i < 3; ++i) v[i] *= limit / n;
  return true;
}

// Moves `previous` toward `target` by at most `max_step` in norm (direction of the change kept);
// writes the result to `target`.
void limit_step(double target[3], const double previous[3], double max_step) {
  double change[3], n = 0;
  for (int i = 0; i < 3; ++i) {
    change[i] = target[i] - previous[i];
    n += change[i] * change[i];
  }
  n = std::sqrt(n);
  if (n <= max_step) return;
  for (int i = 0; i < 3; ++i) target[i] = previous[i] + change[i] * (max_step / n);
}

// Rotation vector of a * conj(b): the small rotation that takes b to a (world frame).
void rotation_error(const double a[4], const double b[4], double out[3]) {
  // q = a * conj(b)
  double w = a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3];
  double x = -a[0] * b[1] + a[1] * b[0] - a[2] * b[3] + a[3] * b[2];
  double y = -a[0] * b[2] + a[1] * b[3] + a[2] * b[0] - a[3] * b[1];
  double z = -a[0] * b[3] - a[1] * b[2] + a[2] * b[1] + a[3] * b[0];
  if (w < 0) { w = -w; x = -x; y = -y; z = -z; }  // the short way round
  double s = std::sqrt(x * x + y * y + z * z);
  double angle = 2 * std::atan2(s, w);
  double k = s > 1e-12 ? angle / s : 2.0;
  out[0] = k * x; out[1] = k * y; out[2] = k * z;
}

}  // namespace

FakeFirmware::FakeFirmware(const DeviceModel& model, const config::Pose& start, std::uint32_t sequence_modulus)
    : model_(model), sequence_modulus_(sequence_modulus) {
  position_[0] = start.position_m.x;
  position_[1] = start.position_m.y;
  position_[2] = start.position_m.z;
  orientation_[0] = start.orientation.w;
  orientation_[1] = start.orientation.x;
  orientation_[2] = start.orientation.y;
  orientation_[3] = start.orientation.z;
}

void FakeFirmware::raise(std::uint8_t bit, std::uint8_t cause, std::uint32_t detail) {
  if (!(faults_ & bit)) new_fault_ = true;
  faults_ |= bit;
  fault_cause_ = cause;
  fault_detail_ = detail;
}

bool FakeFirmware::receive(const hf_message& m, double t_s) {
  switch (m.type) {
    case HF_MSG_COMMAND:
      if (!hf_seq_accept(&seq_, m.seq, sequence_modulus_)) {
        // a repeated or late frame inside a live stream is ignored; after a silence longer than
        // the watchdog the host has restarted and counts from 0 again
        if ((t_s - last_command_s_) * 1e3 < model_.watchdog_ms) return false;
        std::memset(&seq_, 0, sizeof seq_);
        hf_seq_accept(&seq_, m.seq, sequence_modulus_);
      }
      command_ = m.body.command;
      command_seq_ = m.seq;
      last_command_s_ = t_s;
      record_.command_received = true;
      ++commands_applied_;
      if (command_.flags & HF_CMD_ESTOP) raise(HF_FAULT_ESTOP, 1, 0);
      // explicit recovery only while disabled, so clearing a fault can never switch force on
      if ((command_.flags & HF_CMD_CLEAR_FAULTS) && !(command_.flags & (HF_CMD_ENABLE | HF_CMD_ESTOP))) {
        faults_ = 0;
        watchdog_trip_s_ = -1;
      }
      return false;
    case HF_MSG_ESTOP: raise(HF_FAULT_ESTOP, 1, m.body.estop.reason); return false;
    case HF_MSG_INFO_REQUEST: return true;
    default: return false;  // heartbeats: the command stream is what the watchdog watches
  }
}

void FakeFirmware::reject_frames(std::uint32_t count, double t_s) {
  if (count == 0) return;
  if (bad_window_start_s_ < 0 || (t_s - bad_window_start_s_) * 1e3 > model_.bad_command_window_ms) {
    bad_window_start_s_ = t_s;
    bad_in_window_ = 0;
  }
  bad_in_window_ += count;
  if (bad_in_window_ >= static_cast<std::uint32_t>(model_.bad_command_burst))
    raise(HF_FAULT_BAD_COMMANDS, 2, bad_in_window_);  // detail: invalid frames in the window
}

void FakeFirmware::step(double t_s, double dt_s, const config::PoseTwist& hand) {
  // Command watchdog: silence of watchdog_ms while enabled -> motors off, latched fault.
  const double silence_ms = last_command_s_ < 0 ? 0 : (t_s - last_command_s_) * 1e3;
  // (1e-6 ms absorbs the rounding of t_s; the rule is "watchdog_ms or more without a command")
  if ((command_.flags & HF_CMD_ENABLE) && silence_ms >= model_.watchdog_ms - 1e-6 &&
      !(faults_ & HF_FAULT_COMMAND_WATCHDOG)) {
    raise(HF_FAULT_COMMAND_WATCHDOG, 0, static_cast<std::uint32_t>(silence_ms));
    watchdog_trip_s_ = t_s;
    watchdog_trip_last_command_s_ = last_command_s_;
  }
  motors_on_ = (command_.flags & HF_CMD_ENABLE) && faults_ == 0;

  double force[3] = {0, 0, 0}, torque[3] = {0, 0, 0};
  if (motors_on_) {
    std::memcpy(force, command_.force_n, sizeof force);
    std::memcpy(torque, command_.torque_nm, sizeof torque);
  }
  saturated_ = limit_norm(force, model_.max_force_n);
  saturated_ = limit_norm(torque, model_.max_torque_nm) || saturated_;
  // The rate limit holds against any sender (a foreign command on the bus included); the step
  // to zero when the motors go off is the safe one and is taken at once.
  if (motors_on_) {
    limit_step(force, applied_force_, model_.max_force_rate_n_per_s * dt_s);
    limit_step(torque, applied_torque_, model_.max_torque_rate_nm_per_s * dt_s);
  }
  std::memcpy(applied_force_, force, sizeof force);
  std::memcpy(applied_torque_, torque, sizeof torque);

  // Translation: m a = F_motor + K_h (x_hand - x) + D_h (v_hand - v) - b v (semi-implicit Euler).
  const double target[3] = {hand.pose.position_m.x, hand.pose.position_m.y, hand.pose.position_m.z};
  const double target_v[3] = {hand.linear_velocity_m_s.x, hand.linear_velocity_m_s.y, hand.linear_velocity_m_s.z};
  at_wall_ = false;
  for (int i = 0; i < 3; ++i) {
    double hand_force = model_.hand_stiffness_n_per_m * (target[i] - position_[i]) +
                        model_.hand_damping_n_s_per_m * (target_v[i] - velocity_[i]);
    record_.hand_force_n[i] = hand_force;
    double accel = (force[i] + hand_force - model_.handle_damping_n_s_per_m * velocity_[i]) / model_.handle_mass_kg;
    velocity_[i] += accel * dt_s;
    position_[i] += velocity_[i] * dt_s;
    if (std::fabs(position_[i]) > model_.workspace_half_extent_m) {  // mechanical end stop
      position_[i] = std::copysign(model_.workspace_half_extent_m, position_[i]);
      velocity_[i] = 0;
      at_wall_ = true;
    }
  }
  // Rotation: I w' = tau_motor + K_r * err + D_r (w_hand - w) - b_r w; q' = 0.5 (0,w) q.
  const double target_q[4] = {hand.pose.orientation.w, hand.pose.orientation.x, hand.pose.orientation.y,
                              hand.pose.orientation.z};
  const double target_w[3] = {hand.angular_velocity_rad_s.x, hand.angular_velocity_rad_s.y,
                              hand.angular_velocity_rad_s.z};
  double err[3];
  rotation_error(target_q, orientation_, err);
  for (int i = 0; i < 3; ++i) {
    double hand_torque = model_.hand_angular_stiffness_nm_per_rad * err[i] +
                         model_.hand_angular_damping_nm_s_per_rad * (target_w[i] - angular_velocity_[i]);
    double accel = (torque[i] + hand_torque - model_.handle_angular_damping_nm_s_per_rad * angular_velocity_[i]) /
                   model_.handle_inertia_kg_m2;
    angular_velocity_[i] += accel * dt_s;
  }
  const double* w = angular_velocity_;
  double* q = orientation_;
  double dq[4] = {-w[0] * q[1] - w[1] * q[2] - w[2] * q[3], w[0] * q[0] + w[1] * q[3] - w[2] * q[2],
                  w[1] * q[0] + w[2] * q[1] - w[0] * q[3], w[2] * q[0] + w[0] * q[2] - w[1] * q[1]};
  double n = 0;
  for (int i = 0; i < 4; ++i) { q[i] += 0.5 * dq[i] * dt_s; n += q[i] * q[i]; }
  n = std::sqrt(n);
  for (int i = 0; i < 4; ++i) q[i] /= n;

  record_.t_s = t_s;
  record_.command_seq = command_seq_;
  record_.command = command_;
  std::memcpy(record_.applied_force_n, force, sizeof force);
  std::memcpy(record_.applied_torque_nm, torque, sizeof torque);
  record_.status = status();
  record_.faults = faults_;
}

std::uint8_t FakeFirmware::status() const {
  std::uint8_t s = 0;
  if (motors_on_) s |= HF_STATUS_MOTORS_ENABLED;
  if (faults_) s |= HF_STATUS_FAULTED;
  if (faults_ & HF_FAULT_ESTOP) s |= HF_STATUS_ESTOP_LATCHED;
  if (faults_ & HF_FAULT_COMMAND_WATCHDOG) s |= HF_STATUS_WATCHDOG_TRIPPED;
  if (saturated_) s |= HF_STATUS_FORCE_SATURATED;
  if (at_wall_) s |= HF_STATUS_AT_WORKSPACE_LIMIT;
  return s;
}

hf_state FakeFirmware::state(std::uint32_t device_time_us) const {
  hf_state s;
  std::memset(&s, 0, sizeof s);
  s.device_time_us = device_time_us;
  auto clamp = [](double v, double limit) { return v > limit ? limit : v < -limit ? -limit : v; };
  for (int i = 0; i < 3; ++i) {
    // the wire carries +-0.655 m, +-3.27 m/s, +-32.7 rad/s; a real arm's encoders saturate too
    s.position_m[i] = clamp(position_[i], 0.655);
    s.linear_velocity_m_s[i] = clamp(velocity_[i], 3.27);
    s.angular_velocity_rad_s[i] = clamp(angular_velocity_[i], 32.7);
  }
  std::memcpy(s.orientation, orientation_, sizeof s.orientation);
  s.command_echo = static_cast<std::uint8_t>(command_seq_);
  s.status = status();
  s.fault = faults_;
  return s;
}

hf_info FakeFirmware::info() const {
  hf_info n;
  std::memset(&n, 0, sizeof n);
  n.vendor_id = 0x1209;
  n.product_id = 0x4846;
  n.firmware_version = 0x0100;
  n.protocol_version = HF_PROTOCOL_VERSION;
  n.watchdog_ms = static_cast<std::uint8_t>(model_.watchdog_ms > 255 ? 255 : model_.watchdog_ms);
  n.max_force_n = model_.max_force_n;
  n.max_torque_nm = model_.max_torque_nm;
  n.workspace_half_extent_m = model_.workspace_half_extent_m;
  return n;
}

hf_fault FakeFirmware::fault_report(double) const {
  hf_fault f;
  std::memset(&f, 0, sizeof f);
  f.faults = faults_;
  f.cause = fault_cause_;
  f.detail = fault_detail_;
  return f;
}

}  // namespace hapfluid::fake
