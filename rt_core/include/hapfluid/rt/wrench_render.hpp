// Turning sim samples (60-1000 Hz) into a wrench every 1 kHz tick, per device (rig: wrench_mode).
//
// interpolate: when sample n arrives at r_n, the output moves in a straight line from its current
//   value to W_n over one sample period T (the measured arrival interval), then holds. The output
//   is continuous, a convex combination of the samples (no overshoot), and lags the sim by about
//   one period (T + one tick). Smooth, but everything the hand feels is a period old: stiff
//   contacts rendered this way need damping b > K T / 2 (at 60 Hz ~17x more than at 1 kHz).
//
// coupling: the sim sends, with each sample, the local model of the virtual coupling at the pose
//   it used: F0/tau0 at x0/q0 with twist v0/w0, stiffness K and damping D, and the twist
//   vref/wref of the grasp the spring is anchored to. The loop evaluates
//     F   = F0   - K  (x - x0 - vref h)                + D  (v0 - v)
//     tau = tau0 - Kr rotvec(q (exp(wref h) q0)^-1)    + Dr (w0 - w)
//   against the current device pose every tick, h being the time since the device pose x0 was
//   read, in simulated time (the loop scales wall time by the sim's pace, so a sim slower than
//   real time does not drive the anchor ahead of its bodies). The spring is thus closed at 1 kHz
//   where passivity needs it, and a device step changes the wrench within one tick. (The stiffness term opposes the displacement: the spring pulls the
//   hand back toward the pose the sim solved for.) The anchor moves on with the grasp between
//   samples: a hand carrying its body along at constant speed stretches the spring by nothing
//   the sim did not, where a fixed anchor would add K v h, a drag that grows with the sample's
//   age. K, Kr, D and Dr are capped by the rig's max closed-loop stiffness and damping; F0 still
//   updates at the sim rate.
#pragma once

#include <cstdint>

#include "hapfluid/rt/workspace.hpp"
#include "hapfluid/safety/wrench.hpp"
#include "hapfluid/shm/layouts.hpp"

namespace hapfluid::rt {

class InterpolatingRenderer {
 public:
  // `initial_period_ns`: assumed sample period until two samples have arrived.
  explicit InterpolatingRenderer(std::uint64_t initial_period_ns = 16'666'667,
                                 std::uint64_t min_period_ns = 1'000'000, std::uint64_t max_period_ns = 100'000'000)
      : period_ns_(initial_period_ns), min_period_ns_(min_period_ns), max_period_ns_(max_period_ns) {}

  // A new sample with wrench `w` arrived at `receive_ns`. Call before render() of the same tick.
  void on_sample(const Wrench& w, std::uint64_t receive_ns);
  Wrench render(std::uint64_t now_ns) const;
  // Restart from zero (e.g. after the sim restarted).
  void reset();
  std::uint64_t period_ns() const { return period_ns_; }

 private:
  Wrench start_;
  Wrench target_;
  std::uint64_t start_ns_ = 0;
  std::uint64_t last_receive_ns_ = 0;
  std::uint64_t period_ns_;
  std::uint64_t min_period_ns_, max_period_ns_;
  bool have_sample_ = false;
};

// Scene units: the rig's device caps divided by the workspace gain (linear_gain() for K and D,
// angular_gain() for Kr and Dr), since both scale a scene gain into what the hand feels alike.
struct CouplingCaps {
  double max_stiffness_n_per_m;
  double max_angular_stiffness_nm_per_rad;
  double max_damping_n_s_per_m;
  double max_angular_damping_nm_s_per_rad;
};

// Evaluates the local coupling model against the device's current scene-frame pose and twist,
// the anchor moved on for `age_s` of simulated time since the device pose x0 (negative before
// it; the caller bounds it, and scales wall time by the sim's pace; non-finite: 0).
// Negative K/D are treated as 0 (they would be active); K or Kr above its cap is reduced and
// sets safety::flag_stiffness_capped in `flags`, D or Dr above its cap safety::flag_damping_capped.
Wrench render_coupling(const shm::CouplingModel& model, const Twist6& device_scene, const CouplingCaps& caps,
                       double age_s, std::uint32_t& flags);

}  // namespace hapfluid::rt
