#include "hapfluid/rt/wrench_render.hpp"

#include <algorithm>

namespace hapfluid::rt {

void InterpolatingRenderer::on_sample(const Wrench& w, std::uint64_t receive_ns) {
  if (have_sample_ && receive_ns > last_receive_ns_) {
    // Smoothed arrival interval: one late sample should not stretch the next ramp much.
    std::uint64_t interval = std::clamp(receive_ns - last_receive_ns_, min_period_ns_, max_period_ns_);
    period_ns_ = (3 * period_ns_ + interval) / 4;
  }
  start_ = render(receive_ns);  // continue from where the output is now
  target_ = w;
  start_ns_ = receive_ns;
  last_receive_ns_ = receive_ns;
  have_sample_ = true;
}

Wrench InterpolatingRenderer::render(std::uint64_t now_ns) const {
  if (!have_sample_) return {};
  if (now_ns <= start_ns_) return start_;
  double s = double(now_ns - start_ns_) / double(period_ns_);
  if (s >= 1.0) return target_;
  return start_ + s * (target_ - start_);
}

void InterpolatingRenderer::reset() {
  start_ = target_ = {};
  have_sample_ = false;
}

Wrench render_coupling(const shm::CouplingModel& m, const Twist6& d, const CouplingCaps& caps, bool& capped) {
  double k = std::max(0.0, m.stiffness_n_per_m);
  double kr = std::max(0.0, m.angular_stiffness_nm_per_rad);
  double damping = std::max(0.0, m.damping_n_s_per_m);
  double angular_damping = std::max(0.0, m.angular_damping_nm_s_per_rad);
  capped = false;
  if (k > caps.max_stiffness_n_per_m) {
    k = caps.max_stiffness_n_per_m;
    capped = true;
  }
  if (kr > caps.max_angular_stiffness_nm_per_rad) {
    kr = caps.max_angular_stiffness_nm_per_rad;
    capped = true;
  }
  using safety::from;
  V3 dx = d.position_m - from(m.x0_m);
  V3 dtheta = safety::rotation_vector(safety::normalized(d.orientation) *
                                      safety::conjugate(safety::normalized(safety::quat_from(m.q0))));
  V3 force = from(m.force_n) - k * dx + damping * (from(m.v0_m_s) - d.linear_velocity_m_s);
  V3 torque = from(m.torque_nm) - kr * dtheta + angular_damping * (from(m.w0_rad_s) - d.angular_velocity_rad_s);
  return {force, torque};
}

}  // namespace hapfluid::rt
