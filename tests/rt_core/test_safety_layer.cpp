// The safety layer as a whole: property tests with random, hostile and non-finite streams, and
// the watchdog/engage/e-stop behaviours with their timing (1 kHz, rig defaults unless stated).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "hapfluid/safety/safety_layer.hpp"

using namespace hapfluid::safety;

namespace {

constexpr std::uint64_t kTickNs = 1'000'000;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Drives a SafetyLayer tick by tick with a healthy link and fresh sim samples unless told.
struct Harness {
  SafetyConfig config;
  SafetyLayer layer;
  std::uint64_t now_ns = 0;
  double sim_age_ms = 0;
  explicit Harness(SafetyConfig c = {}) : config(c), layer(config) {}
  SafetyOutput tick(Wrench command, bool fresh_frame = true, bool sim_fresh = true) {
    now_ns += kTickNs;
    sim_age_ms = sim_fresh ? 0 : sim_age_ms + 1.0;
    SafetyInput in;
    in.now_ns = now_ns;
    in.command = command;
    in.fresh_frame = fresh_frame;
    in.sim_age_ms = sim_age_ms;
    in.deadman_pressed = deadman;
    in.estop_input = estop;
    return layer.step(in);
  }
  // Runs until engaged at `command` (link recovery + engage ramp) and returns the last output.
  SafetyOutput settle(Wrench command, int ticks = 600) {
    SafetyOutput out;
    for (int i = 0; i < ticks; ++i) out = tick(i < 150 ? Wrench{} : command);
    return out;
  }
  bool deadman = true;
  bool estop = false;
};

double max_abs_change(const Wrench& a, const Wrench& b) { return norm(a.force_n - b.force_n); }

Wrench hostile(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-1, 1);
  std::uniform_int_distribution<int> kind(0, 9);
  auto vec = [&](double scale) { return V3{scale * u(rng), scale * u(rng), scale * u(rng)}; };
  switch (kind(rng)) {
    case 0: return {{kNaN, 0, 0}, {}};
    case 1: return {vec(1e9), vec(1e9)};
    case 2: return {{std::numeric_limits<double>::infinity(), 1, 1}, vec(1)};
    case 3: return {vec(1e-300), vec(1e-300)};
    case 4: return {{1e308, -1e308, 1e308}, {0, 0, -1e308}};
    case 5: return {vec(100), vec(10)};
    default: return {vec(12), vec(0.6)};
  }
}

}  // namespace

TEST(SafetyLayer, HostileStreamsNeverExceedAnyLimitNorChangeFasterThanTheRateLimit) {
  // Whatever the sim sends (random, huge, denormal, NaN, Inf), with random link drop-outs,
  // sim stalls and NaN velocities: every output is within every limit, and between two ticks the
  // force changes by at most max_force_rate * T (1 N) and the torque by 0.05 N*m, except a
  // hard-zero (fault/e-stop/deadman), which drops straight to zero.
  SafetyConfig config;
  config.max_force_axis_n = {10, 6, 8};
  config.max_torque_axis_nm = {0.5, 0.3, 0.4};
  for (std::uint64_t seed = 1; seed <= 30; ++seed) {
    std::mt19937_64 rng(seed);
    std::bernoulli_distribution drop(0.02), stall(0.01), nan_velocity(0.01);
    Harness h(config);
    Wrench previous{};
    for (int k = 0; k < 4000; ++k) {
      SafetyInput in;
      h.now_ns += kTickNs;
      in.now_ns = h.now_ns;
      in.command = hostile(rng);
      in.fresh_frame = !drop(rng);
      in.linear_velocity_m_s = nan_velocity(rng) ? V3{kNaN, 0, 0} : V3{0.1, -0.2, 0.05};
      h.sim_age_ms = stall(rng) ? 200 : 0;
      in.sim_age_ms = h.sim_age_ms;
      SafetyOutput out = h.layer.step(in);
      ASSERT_TRUE(within_limits(out.wrench, config, 1e-9)) << "seed " << seed << " tick " << k;
      bool dropped_to_zero = out.wrench == Wrench{} && (out.flags & flag_hard_zero);
      if (!dropped_to_zero) {
        ASSERT_LE(norm(out.wrench.force_n - previous.force_n), 1.0 * (1 + 1e-9)) << "seed " << seed << " tick " << k;
        ASSERT_LE(norm(out.wrench.torque_nm - previous.torque_nm), 0.05 * (1 + 1e-9));
      }
      previous = out.wrench;
    }
  }
}

TEST(SafetyLayer, StartsAtZeroAndEngagesOnlyOnceTheCommandIsSmall) {
  // Switching on while the sim pushes 5 N must not jerk the hand: the output waits for the
  // command to drop below engage_threshold_n (1 N), then ramps in over engage_ramp_ms (200 ms).
  Harness h;
  SafetyOutput out;
  for (int i = 0; i < 300; ++i) out = h.tick({{5, 0, 0}, {}});
  EXPECT_EQ(out.wrench, Wrench{});
  EXPECT_TRUE(out.flags & flag_waiting_to_engage);
  for (int i = 0; i < 10; ++i) out = h.tick({{0.5, 0, 0}, {}});
  EXPECT_TRUE(out.flags & flag_engaging);
  EXPECT_LT(out.wrench.force_n.x, 0.5 * 11.0 / 200.0 + 1e-9) << "ramping, not jumping";
  for (int i = 0; i < 200; ++i) out = h.tick({{0.5, 0, 0}, {}});
  EXPECT_NEAR(out.wrench.force_n.x, 0.5, 1e-9);
  EXPECT_FALSE(out.flags & (flag_engaging | flag_waiting_to_engage));
}

TEST(SafetyLayer, StaleSimRampsToZeroWithinTheConfiguredTimeAndResumesSmoothly) {
  // sim_stale_ms = 50, sim_ramp_down_ms = 100: from the moment the newest sample is 50 ms old the
  // wrench falls monotonically and is zero within 100 ms (+1 tick). When samples return it
  // rises back without any step larger than the rate limit.
  Harness h;
  SafetyOutput out = h.settle({{8, 0, 0}, {}});
  ASSERT_NEAR(out.wrench.force_n.x, 8.0, 1e-9);
  int stale_tick = -1, zero_tick = -1;
  double previous = out.wrench.force_n.x;
  for (int k = 0; k < 300; ++k) {
    out = h.tick({{8, 0, 0}, {}}, true, /*sim_fresh=*/false);
    if (stale_tick < 0 && (out.faults & fault_sim_stale)) stale_tick = k;
    EXPECT_LE(out.wrench.force_n.x, previous + 1e-12) << "monotone ramp-down";
    previous = out.wrench.force_n.x;
    if (zero_tick < 0 && out.wrench.force_n.x == 0) zero_tick = k;
  }
  ASSERT_GE(stale_tick, 0);
  EXPECT_NEAR(stale_tick, 50, 1) << "the watchdog fires after sim_stale_ms";
  ASSERT_GE(zero_tick, 0);
  EXPECT_LE(zero_tick - stale_tick, 100 + 1);
  EXPECT_FALSE(out.flags & flag_hard_zero) << "staleness ramps; it is not a hard stop";

  Wrench last = out.wrench;
  for (int k = 0; k < 400; ++k) {
    out = h.tick({{8, 0, 0}, {}});
    EXPECT_LE(max_abs_change(out.wrench, last), 1.0 + 1e-9);
    last = out.wrench;
  }
  EXPECT_NEAR(out.wrench.force_n.x, 8.0, 1e-9) << "resumed";
  EXPECT_EQ(out.faults, 0u);
}

TEST(SafetyLayer, LinkLossZeroesAtOnceAndRecoversOnlyAfterAHealthyLinkAndARamp) {
  // link_timeout_ms = 5: no valid frame for 5 ms is a fault and the output is exactly zero.
  // Frames back: the fault clears after link_recover_ms (100 ms) of healthy frames; the wrench
  // then re-engages only once the command is small and ramps in.
  Harness h;
  SafetyOutput out = h.settle({{8, 0, 0}, {}});
  ASSERT_NEAR(out.wrench.force_n.x, 8.0, 1e-9);
  int fault_tick = -1;
  for (int k = 0; k < 20; ++k) {
    out = h.tick({{8, 0, 0}, {}}, /*fresh_frame=*/false);
    if (fault_tick < 0 && (out.faults & fault_link_timeout)) fault_tick = k;
  }
  ASSERT_GE(fault_tick, 0);
  EXPECT_LE(fault_tick, 6) << "within link_timeout_ms + 1 tick";
  EXPECT_EQ(out.wrench, Wrench{});
  EXPECT_FALSE(out.enable);
  for (int k = 0; k < 99; ++k) out = h.tick({{8, 0, 0}, {}});
  EXPECT_TRUE(out.faults & fault_link_timeout) << "not yet 100 ms of healthy link";
  for (int k = 0; k < 5; ++k) out = h.tick({{8, 0, 0}, {}});
  EXPECT_FALSE(out.faults & fault_link_timeout);
  EXPECT_EQ(out.wrench, Wrench{}) << "8 N is above the engage threshold: still waiting";
  EXPECT_TRUE(out.flags & flag_waiting_to_engage);
  out = h.tick({{0.2, 0, 0}, {}});
  EXPECT_TRUE(out.flags & flag_engaging);
}

TEST(SafetyLayer, InvalidDeviceStateIsALinkFault) {
  Harness h;
  h.settle({{2, 0, 0}, {}});
  SafetyInput in;
  in.now_ns = h.now_ns + kTickNs;
  in.command = {{2, 0, 0}, {}};
  in.fresh_frame = true;
  in.sim_age_ms = 0;
  in.angular_velocity_rad_s = {0, kNaN, 0};
  SafetyOutput out = h.layer.step(in);
  EXPECT_TRUE(out.faults & fault_link_invalid);
  EXPECT_EQ(out.wrench, Wrench{});
}

TEST(SafetyLayer, DeadmanReleaseZeroesImmediatelyWhenRequired) {
  SafetyConfig c;
  c.require_deadman = true;
  Harness h(c);
  SafetyOutput out = h.settle({{3, 0, 0}, {}});
  ASSERT_NEAR(out.wrench.force_n.x, 3.0, 1e-9);
  h.deadman = false;
  out = h.tick({{3, 0, 0}, {}});
  EXPECT_EQ(out.wrench, Wrench{});
  EXPECT_TRUE(out.flags & flag_deadman_released);
}

TEST(SafetyLayer, EstopLatchesUntilAnExplicitResetWithTheButtonReleased) {
  Harness h;
  SafetyOutput out = h.settle({{0.5, 0, 0}, {}});
  ASSERT_GT(out.wrench.force_n.x, 0.4);
  h.estop = true;
  out = h.tick({{0.5, 0, 0}, {}});
  EXPECT_EQ(out.wrench, Wrench{});
  EXPECT_TRUE(out.estop);
  EXPECT_FALSE(h.layer.reset_estop()) << "refused while the button is held";
  h.estop = false;
  for (int i = 0; i < 500; ++i) out = h.tick({{0.5, 0, 0}, {}});
  EXPECT_TRUE(out.faults & fault_estop) << "releasing the button does not clear a latched e-stop";
  EXPECT_EQ(out.wrench, Wrench{});
  EXPECT_TRUE(h.layer.reset_estop());
  for (int i = 0; i < 300; ++i) out = h.tick({{0.5, 0, 0}, {}});
  EXPECT_NEAR(out.wrench.force_n.x, 0.5, 1e-9);
  h.layer.request_estop();
  out = h.tick({{0.5, 0, 0}, {}});
  EXPECT_TRUE(out.estop);
}

TEST(SafetyLayer, DescribeListsEveryLimitAndItsSource) {
  std::string text = describe(SafetyConfig{});
  for (const char* key : {"max_force_n", "max_torque_rate_nm_per_s", "sim_stale_ms", "link_recover_ms = 100 (rig)",
                          "passivity"})
    EXPECT_NE(text.find(key), std::string::npos) << key;
  EXPECT_EQ(fault_names(fault_estop | fault_sim_stale), "estop|sim_stale");
  EXPECT_EQ(flag_names(0), "-");
}

TEST(SafetyLayer, StalenessRampFollowsElapsedTimeWhenTicksAreSkipped) {
  // An overloaded loop that only runs every 5 ms must still reach zero within sim_ramp_down_ms
  // (100 ms) of the watchdog firing, not 5x later.
  Harness h;
  h.settle({{8, 0, 0}, {}});
  SafetyInput in;
  in.command = {{8, 0, 0}, {}};
  in.fresh_frame = true;
  std::uint64_t stale_since = h.now_ns;
  SafetyOutput out;
  for (int k = 1; k <= 40; ++k) {
    in.now_ns = h.now_ns + k * 5 * kTickNs;
    in.sim_age_ms = double(in.now_ns - stale_since) * 1e-6;
    out = h.layer.step(in);
    if (in.sim_age_ms >= 50 + 100 + 5) {
      EXPECT_EQ(out.wrench, Wrench{}) << "at " << in.sim_age_ms << " ms";
    }
  }
}
