// Time-domain passivity observer and controller (Hannaford & Ryu 2002, "Time-domain passivity
// control of haptic interfaces", IEEE Trans. Robotics and Automation 18(1)).
//
// Observer: the energy absorbed by the virtual environment from the hand,
//   E(n) = E(n-1) - (F(n)·v(n) + tau(n)·w(n)) T,
// with F/tau the wrench the device applies to the hand and v/w the handle's twist. A passive
// environment keeps E >= 0; E < 0 means the rendering (sample-and-hold, delays, a stiff local
// model at a low sim rate) has injected energy into the hand.
// Controller: when E < 0 it adds just enough damping, F' = F - alpha v, to dissipate -E within one
// tick, alpha capped by the configured maximum. E is capped from above (an energy reservoir) so a
// long passive stretch cannot hide a later active one. E starts full (at the cap): from E = 0 a
// plain static push (the weight of a held bowl moving the hand along it) would count as active
// and be damped at once; with the reservoir the hand may receive at most the cap (0.2 J by
// default, 2 cm at a 10 N limit) before damping starts, which still stops any limit cycle.
#pragma once

#include <cstdint>

#include "hapfluid/safety/safety_config.hpp"
#include "hapfluid/safety/wrench.hpp"

namespace hapfluid::safety {

class PassivityController {
 public:
  explicit PassivityController(const SafetyConfig& config)
      : config_(&config), energy_j_(config.passivity_energy_cap_j) {}
  // Adds damping to `command` if the observed energy is negative. Sets flag_passivity_damping.
  Wrench apply(const Wrench& command, V3 velocity_m_s, V3 angular_velocity_rad_s, std::uint32_t& flags) const;
  // Accounts for the wrench that actually reached the device this tick.
  void observe(const Wrench& output, V3 velocity_m_s, V3 angular_velocity_rad_s);
  double energy_j() const { return energy_j_; }
  void reset() { energy_j_ = config_->passivity_energy_cap_j; }

 private:
  const SafetyConfig* config_;
  double energy_j_;
};

}  // namespace hapfluid::safety
