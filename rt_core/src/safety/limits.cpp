#include "hapfluid/safety/limits.hpp"

#include <algorithm>

namespace hapfluid::safety {
namespace {

// Uniform scale bringing `v` inside both its norm ball and its axis box.
V3 limit_vector(V3 v, double max_norm, V3 max_axis, std::uint32_t norm_flag, std::uint32_t axis_flag,
                std::uint32_t& flags) {
  double n = norm(v);
  if (n > max_norm) {
    v = (max_norm / n) * v;
    flags |= norm_flag;
  }
  double scale = 1.0;
  for (int i = 0; i < 3; ++i) {
    double a = std::abs(v[i]);
    if (a > max_axis[i]) scale = std::min(scale, max_axis[i] / a);
  }
  if (scale < 1.0) {
    v = scale * v;
    flags |= axis_flag;
  }
  return v;
}

bool vector_within(V3 v, double max_norm, V3 max_axis, double tolerance) {
  if (norm(v) > max_norm * (1 + tolerance)) return false;
  for (int i = 0; i < 3; ++i)
    if (std::abs(v[i]) > max_axis[i] * (1 + tolerance)) return false;
  return true;
}

}  // namespace

Wrench zero_if_nonfinite(const Wrench& command, std::uint32_t& flags) {
  if (finite(command)) return command;
  flags |= flag_nonfinite_input;
  return {};
}

Wrench limit_magnitude(const Wrench& command, const SafetyConfig& c, std::uint32_t& flags) {
  return {limit_vector(command.force_n, c.max_force_n, c.max_force_axis_n, flag_force_norm_limited,
                       flag_force_axis_limited, flags),
          limit_vector(command.torque_nm, c.max_torque_nm, c.max_torque_axis_nm, flag_torque_norm_limited,
                       flag_torque_axis_limited, flags)};
}

Wrench limit_rate(const Wrench& target, const Wrench& previous, const SafetyConfig& c, std::uint32_t& flags) {
  V3 df = target.force_n - previous.force_n;
  V3 dt = target.torque_nm - previous.torque_nm;
  double max_df = c.max_force_rate_n_per_s * c.period_s;
  double max_dt = c.max_torque_rate_nm_per_s * c.period_s;
  double nf = norm(df), nt = norm(dt);
  if (nf > max_df) {
    df = (max_df / nf) * df;
    flags |= flag_rate_limited;
  }
  if (nt > max_dt) {
    dt = (max_dt / nt) * dt;
    flags |= flag_rate_limited;
  }
  return {previous.force_n + df, previous.torque_nm + dt};
}

bool within_limits(const Wrench& w, const SafetyConfig& c, double tolerance) {
  return finite(w) && vector_within(w.force_n, c.max_force_n, c.max_force_axis_n, tolerance) &&
         vector_within(w.torque_nm, c.max_torque_nm, c.max_torque_axis_nm, tolerance);
}

}  // namespace hapfluid::safety
