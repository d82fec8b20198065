// The memoryless safety stages and the passivity controller, one behaviour per test.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "hapfluid/safety/limits.hpp"
#include "hapfluid/safety/passivity.hpp"

using namespace hapfluid::safety;

namespace {
SafetyConfig defaults() {
  SafetyConfig c;  // 10 N / 0.5 N*m norm and per axis, 1000 N/s, 50 N*m/s, 1 kHz
  return c;
}
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();
}  // namespace

TEST(SafetyLimits, NonFiniteComponentZeroesTheWholeWrench) {
  // A NaN in one axis leaves no trustworthy direction: the safe command is zero, and it is flagged.
  for (double bad : {kNaN, kInf, -kInf}) {
    std::uint32_t flags = 0;
    Wrench w = zero_if_nonfinite({{1, bad, 2}, {0.1, 0, 0}}, flags);
    EXPECT_EQ(w, Wrench{});
    EXPECT_TRUE(flags & flag_nonfinite_input);
  }
  std::uint32_t flags = 0;
  EXPECT_EQ(zero_if_nonfinite({{1, 2, 3}, {0, 0, kNaN}}, flags), Wrench{});
}

TEST(SafetyLimits, NormLimitPreservesDirection) {
  // 50 N along (3,0,4)/5 on a 10 N device becomes 10 N along the same direction: (6, 0, 8) N.
  std::uint32_t flags = 0;
  Wrench w = limit_magnitude({{30, 0, 40}, {}}, defaults(), flags);
  EXPECT_NEAR(w.force_n.x, 6.0, 1e-12);
  EXPECT_NEAR(w.force_n.z, 8.0, 1e-12);
  EXPECT_TRUE(flags & flag_force_norm_limited);
  EXPECT_FALSE(flags & flag_torque_norm_limited);
}

TEST(SafetyLimits, PerAxisLimitScalesUniformly) {
  // A weak z axis (2 N) on a 10 N device: (3, 0, 4) N is scaled by 2/4 to (1.5, 0, 2) N, same direction.
  SafetyConfig c = defaults();
  c.max_force_axis_n = {10, 10, 2};
  std::uint32_t flags = 0;
  Wrench w = limit_magnitude({{3, 0, 4}, {}}, c, flags);
  EXPECT_NEAR(w.force_n.x, 1.5, 1e-12);
  EXPECT_NEAR(w.force_n.z, 2.0, 1e-12);
  EXPECT_TRUE(flags & flag_force_axis_limited);
  EXPECT_FALSE(flags & flag_force_norm_limited);
}

TEST(SafetyLimits, TorqueIsLimitedIndependentlyOfForce) {
  std::uint32_t flags = 0;
  Wrench w = limit_magnitude({{1, 0, 0}, {0, 0, -2}}, defaults(), flags);
  EXPECT_NEAR(w.torque_nm.z, -0.5, 1e-12);
  EXPECT_NEAR(w.force_n.x, 1.0, 1e-12);
  EXPECT_TRUE(flags & flag_torque_norm_limited);
}

TEST(SafetyLimits, RateLimitBoundsTheChangePerTickAndKeepsItsDirection) {
  // 1000 N/s at 1 kHz: at most 1 N of change per tick, along the requested change.
  std::uint32_t flags = 0;
  Wrench w = limit_rate({{10, 0, 0}, {0, 0, 1}}, {{0, 0, 0}, {0, 0, 0}}, defaults(), flags);
  EXPECT_NEAR(w.force_n.x, 1.0, 1e-12);
  EXPECT_NEAR(w.torque_nm.z, 0.05, 1e-12);  // 50 N*m/s * 1 ms
  EXPECT_TRUE(flags & flag_rate_limited);
  flags = 0;
  Wrench small = limit_rate({{0.5, 0, 0}, {}}, {}, defaults(), flags);
  EXPECT_EQ(small.force_n.x, 0.5);
  EXPECT_EQ(flags, 0u);
}

TEST(Passivity, DampingIsAddedOnlyAfterTheEnvironmentTurnedActive) {
  SafetyConfig c = defaults();
  c.passivity_energy_cap_j = 0.0;  // no reservoir: react to the first joule
  PassivityController pc(c);
  std::uint32_t flags = 0;
  V3 v{0.1, 0, 0};
  // Passive so far (E = 0): the command passes unchanged.
  EXPECT_EQ(pc.apply({{1, 0, 0}, {}}, v, {}, flags).force_n.x, 1.0);
  EXPECT_EQ(flags, 0u);
  // The device pushed 1 N along a 0.1 m/s motion for one tick: 0.1 mJ went into the hand.
  pc.observe({{1, 0, 0}, {}}, v, {});
  EXPECT_NEAR(pc.energy_j(), -1e-4, 1e-12);
  // Next tick: damping alpha = 1e-4 J / (1 ms * 0.01 m^2/s^2) = 10 N*s/m opposes the motion.
  Wrench damped = pc.apply({{1, 0, 0}, {}}, v, {}, flags);
  EXPECT_NEAR(damped.force_n.x, 1.0 - 10 * 0.1, 1e-9);
  EXPECT_TRUE(flags & flag_passivity_damping);
}

TEST(Passivity, ControllerKeepsAnEnergyGeneratingRenderingFromPumpingTheHand) {
  // A rendering with negative damping (F = +5 N*s/m * v) is a pure energy source. Over 10 s of
  // 2 Hz hand oscillation it would deliver joules; with the controller the hand receives at most
  // the observer's initial reservoir (0.2 J) plus one tick's worth.
  SafetyConfig c = defaults();
  auto energy_to_hand = [&](bool enabled) {
    c.passivity_enabled = enabled;
    PassivityController pc(c);
    double energy = 0;
    for (int k = 0; k < 10000; ++k) {
      double t = k * 1e-3;
      V3 v{0.2 * std::sin(2 * M_PI * 2 * t), 0, 0};
      std::uint32_t flags = 0;
      Wrench out = pc.apply({5.0 * v, {}}, v, {}, flags);
      pc.observe(out, v, {});
      energy += dot(out.force_n, v) * 1e-3;
    }
    return energy;
  };
  EXPECT_GT(energy_to_hand(false), 1.0) << "control: the rendering really is active";
  EXPECT_LT(energy_to_hand(true), c.passivity_energy_cap_j + 0.01);
}
