#include "hapfluid/safety/passivity.hpp"

#include <algorithm>

#include "hapfluid/safety/flags.hpp"

namespace hapfluid::safety {

Wrench PassivityController::apply(const Wrench& command, V3 v, V3 w, std::uint32_t& flags) const {
  const SafetyConfig& c = *config_;
  if (!c.passivity_enabled || energy_j_ >= 0) return command;
  // Split the dissipation between translation and rotation in the ratio of their damping caps:
  // alpha_r = ratio * alpha_l, and alpha_l (|v|^2 + ratio |w|^2) T = -E.
  double ratio = c.passivity_max_damping_nm_s_per_rad / c.passivity_max_damping_n_s_per_m;
  double denominator = (dot(v, v) + ratio * dot(w, w)) * c.period_s;
  if (!(denominator > 1e-15)) return command;  // handle at rest: no energy flows, nothing to damp
  double alpha = std::min(-energy_j_ / denominator, c.passivity_max_damping_n_s_per_m);
  flags |= flag_passivity_damping;
  return {command.force_n - alpha * v, command.torque_nm - (ratio * alpha) * w};
}

void PassivityController::observe(const Wrench& output, V3 v, V3 w) {
  double power_to_hand_w = dot(output.force_n, v) + dot(output.torque_nm, w);
  if (!std::isfinite(power_to_hand_w)) return;
  energy_j_ = std::min(energy_j_ - power_to_hand_w * config_->period_s, config_->passivity_energy_cap_j);
}

}  // namespace hapfluid::safety
