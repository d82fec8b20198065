#include "hapfluid/rt/wrench_render.hpp"

#include <algorithm>
#include <cmath>

#include "hapfluid/safety/flags.hpp"

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

namespace {
// A gain above its cap is reduced to it and `flag` set; a negative one (active) becomes 0.
double capped_gain(double gain, double cap, std::uint32_t flag, std::uint32_t& flags) {
  gain = std::max(0.0, gain);
  if (gain <= cap) return gain;
  flags |= flag;
  return cap;
}
}  // namespace

Wrench render_coupling(const shm::CouplingModel& m, const Twist6& d, const CouplingCaps& caps, double age_s,
                       std::uint32_t& flags) {
  const double k = capped_gain(m.stiffness_n_per_m, caps.max_stiffness_n_per_m, safety::flag_stiffness_capped, flags);
  const double kr = capped_gain(m.angular_stiffness_nm_per_rad, caps.max_angular_stiffness_nm_per_rad,
                                safety::flag_stiffness_capped, flags);
  const double damping = capped_gain(m.damping_n_s_per_m, caps.max_damping_n_s_per_m, safety::flag_damping_capped, flags);
  const double angular_damping = capped_gain(m.angular_damping_nm_s_per_rad, caps.max_angular_damping_nm_s_per_rad,
                                             safety::flag_damping_capped, flags);
  using safety::from;
  const double h = std::isfinite(age_s) ? age_s : 0.0;
  // The anchor h later: x0 moved on by vref, q0 turned on by wref (a world-frame rate: on the left).
  V3 dx = d.position_m - from(m.x0_m) - h * from(m.vref_m_s);
  const safety::Quat anchor = safety::quat_from_rotation_vector(h * from(m.wref_rad_s)) *
                              safety::normalized(safety::quat_from(m.q0));
  V3 dtheta = safety::rotation_vector(safety::normalized(d.orientation) * safety::conjugate(anchor));
  // A non-finite anchor rate would be normalised away above: pass it on so the safety layer zeroes it.
  if (!safety::finite(from(m.wref_rad_s))) dtheta = {NAN, NAN, NAN};
  V3 force = from(m.force_n) - k * dx + damping * (from(m.v0_m_s) - d.linear_velocity_m_s);
  V3 torque = from(m.torque_nm) - kr * dtheta + angular_damping * (from(m.w0_rad_s) - d.angular_velocity_rad_s);
  return {force, torque};
}

}  // namespace hapfluid::rt
