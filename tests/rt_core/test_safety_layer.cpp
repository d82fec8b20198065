// The safety layer as a whole: property tests with random, hostile and non-finite streams, and
// the watchdog/engage/e-stop behaviours with their timing (1 kHz, rig defaults unless stated).
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>

#include "hapfluid/config/errors.hpp"
#include "hapfluid/config/rig.hpp"
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
    now_ns += kTickNs + late_ns;
    late_ns = 0;
    sim_age_ms = sim_fresh ? 0 : sim_age_ms + 1.0;
    SafetyInput in;
    in.now_ns = now_ns;
    in.command = command;
    in.fresh_frame = fresh_frame;
    in.sim_age_ms = sim_age_ms;
    in.deadman_pressed = deadman;
    in.estop_input = estop;
    in.sim_restarted = sim_fresh && sim_restarted;
    if (sim_fresh) sim_restarted = false;
    if (fresh_frame) in.echo_round_trip_ms = round_trip_ms;
    return layer.step(in);
  }
  // Runs until engaged at `command` (link recovery 100 ms, small for 50 ms, then the engage ramp
  // under way from zero) and returns the last output.
  SafetyOutput settle(Wrench command, int ticks = 700) {
    SafetyOutput out;
    for (int i = 0; i < ticks; ++i) out = tick(i < 200 ? Wrench{} : command);
    return out;
  }
  bool deadman = true;
  bool estop = false;
  bool sim_restarted = false;  // the next fresh sample comes from a new sim
  std::uint64_t late_ns = 0;   // the next tick wakes this much late (an overrun)
  double round_trip_ms = -1;   // each fresh frame's command round trip (negative: a device without echo)
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

TEST(SafetyLayer, StartsAtZeroAndEngagesOnlyOnceTheCommandIsSmallOrSteady) {
  // Switching on while the sim pushes a large, changing wrench must not jerk the hand: the output
  // waits. A command below engage_threshold_n (1 N) for engage_small_ms (50 ms) engages and
  // ramps in over engage_ramp_ms (200 ms).
  Harness h;
  SafetyOutput out;
  for (int i = 0; i < 300; ++i) out = h.tick({{i % 2 ? 5.0 : 3.0, 0, 0}, {}});  // 2 N peak-to-peak every tick
  EXPECT_EQ(out.wrench, Wrench{});
  EXPECT_TRUE(out.flags & flag_waiting_to_engage);
  for (int i = 0; i < 45; ++i) out = h.tick({{0.5, 0, 0}, {}});
  EXPECT_TRUE(out.flags & flag_waiting_to_engage) << "not yet small for 50 ms";
  for (int i = 0; i < 15; ++i) out = h.tick({{0.5, 0, 0}, {}});
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

  // The same sim, late: it fades back in over engage_ramp_ms (200 ms, 0.04 N per tick at 8 N).
  Wrench last = out.wrench;
  for (int k = 0; k < 300; ++k) {
    out = h.tick({{8, 0, 0}, {}});
    EXPECT_LE(max_abs_change(out.wrench, last), 8.0 / 200.0 + 1e-9) << "tick " << k;
    last = out.wrench;
  }
  EXPECT_NEAR(out.wrench.force_n.x, 8.0, 1e-9) << "resumed";
  EXPECT_EQ(out.faults, 0u);
}

TEST(SafetyLayer, AShortSimStallFadesBackWithoutWaitingForTheEngageGate) {
  // A stall that ends before the ramp-down reached zero is a hiccup: the wrench fades back over
  // engage_ramp_ms (200 ms) at once, without a new hold window.
  Harness h;
  SafetyOutput out = h.settle({{8, 0, 0}, {}});
  for (int k = 0; k < 100; ++k) out = h.tick({{8, 0, 0}, {}}, true, /*sim_fresh=*/false);  // 50 ms stale
  ASSERT_GT(out.wrench.force_n.x, 2.0);
  for (int k = 0; k < 210; ++k) out = h.tick({{8, 0, 0}, {}});
  EXPECT_NEAR(out.wrench.force_n.x, 8.0, 1e-9);
}

TEST(SafetyLayer, LinkLossZeroesAtOnceAndRecoversOnlyAfterAHealthyLinkAndARamp) {
  // link_timeout_ms = 5: no valid frame for 5 ms is a fault and the output is exactly zero.
  // Frames back: the fault clears after link_recover_ms (100 ms) of healthy frames; the wrench
  // then re-engages only once the command is small (or steady for engage_hold_ms) and ramps in.
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
  EXPECT_EQ(out.wrench, Wrench{}) << "8 N is above the engage threshold and not yet steady for 150 ms: waiting";
  EXPECT_TRUE(out.flags & flag_waiting_to_engage);
  for (int k = 0; k < 51; ++k) out = h.tick({{0.2, 0, 0}, {}});
  EXPECT_TRUE(out.flags & flag_engaging) << "small for engage_small_ms (50 ms)";
}

TEST(SafetyLayer, ALoopThatWokeLateLooksForTheFramesSentMeanwhileBeforeBlamingTheLink) {
  // The loop itself stalled 7 ms (longer than link_timeout_ms): its first tick after the stall
  // finds no frame yet, the next one finds the device's frames. That is an overrun of the loop,
  // not a silent device, and the hand keeps its wrench.
  Harness h;
  SafetyOutput out = h.settle({{3, 0, 0}, {}});
  ASSERT_NEAR(out.wrench.force_n.x, 3.0, 1e-9);
  for (int stall = 0; stall < 20; ++stall) {
    h.late_ns = 7 * kTickNs;
    out = h.tick({{3, 0, 0}, {}}, /*fresh_frame=*/false);
    EXPECT_FALSE(out.faults & fault_link_timeout) << "stall " << stall;
    out = h.tick({{3, 0, 0}, {}});
    EXPECT_FALSE(out.faults) << "stall " << stall;
    EXPECT_NEAR(out.wrench.force_n.x, 3.0, 1e-9) << "stall " << stall;
    for (int k = 0; k < 10; ++k) h.tick({{3, 0, 0}, {}});
  }
  // A device that really fell silent during the stall: a fault once the loop has looked for
  // link_timeout_ms worth of its own ticks.
  h.late_ns = 7 * kTickNs;
  out = h.tick({{3, 0, 0}, {}}, false);
  int fault_tick = -1;
  for (int k = 0; k < 10 && fault_tick < 0; ++k) {
    out = h.tick({{3, 0, 0}, {}}, false);
    if (out.faults & fault_link_timeout) fault_tick = k;
  }
  EXPECT_GE(fault_tick, 0);
  EXPECT_LE(fault_tick, 5);
  EXPECT_EQ(out.wrench, Wrench{});
}

TEST(SafetyLayer, ALoopThatLooksTooSeldomFaultsTheLinkOnceTheDevicesOwnWatchdogHasTripped) {
  // Ticks 8 ms apart on a dead link: never 5 looks in a row within link_timeout_ms, but once
  // device_watchdog_ms (20 ms) has passed the device has zeroed its motors: the host says so too.
  Harness h;
  h.settle({{3, 0, 0}, {}});
  SafetyOutput out;
  double silent_ms = 0;
  while (!(out.faults & fault_link_timeout) && silent_ms < 100) {
    h.late_ns = 7 * kTickNs;
    out = h.tick({{3, 0, 0}, {}}, false);
    silent_ms += 8;
  }
  EXPECT_TRUE(out.faults & fault_link_timeout);
  EXPECT_GT(silent_ms, h.config.device_watchdog_ms);
  EXPECT_LE(silent_ms, h.config.device_watchdog_ms + 8);
  EXPECT_EQ(out.wrench, Wrench{});
}

TEST(SafetyLayer, ASteadyDelayOnTheLinkIsALinkFaultThoughItsFramesKeepTheirRate) {
  // Every frame arrives on time, one per tick, but each echoes a command sent 25 ms before: the
  // poses are 25 ms old. Once link_timeout_ms (5) of round trips were all too long the output is
  // zero, and it stays zero for as long as the delay lasts.
  Harness h;
  h.round_trip_ms = 1.2;
  SafetyOutput out = h.settle({{3, 0, 0}, {}});
  ASSERT_NEAR(out.wrench.force_n.x, 3.0, 1e-9);
  ASSERT_FALSE(out.faults);
  h.round_trip_ms = 25;
  int fault_tick = -1;
  for (int k = 0; k < 500; ++k) {
    out = h.tick({{3, 0, 0}, {}});
    if (fault_tick < 0 && (out.faults & fault_link_latency)) fault_tick = k;
    if (fault_tick >= 0) {
      EXPECT_EQ(out.wrench, Wrench{}) << "tick " << k;
    }
  }
  EXPECT_GE(fault_tick, 4) << "not before link_timeout_ms of slow round trips";
  EXPECT_LE(fault_tick, 6) << "within link_timeout_ms + 1 tick";
  EXPECT_FALSE(out.enable);
  EXPECT_EQ(fault_names(out.faults), "link_latency");
  // The delay ends: the link recovers like after any link fault, link_recover_ms later.
  h.round_trip_ms = 1.2;
  int clear_tick = -1;
  for (int k = 0; k < 200 && clear_tick < 0; ++k)
    if (!(h.tick({{0.1, 0, 0}, {}}).faults & fault_link_latency)) clear_tick = k;
  EXPECT_GE(clear_tick, h.config.link_recover_ms - 1);
  EXPECT_LE(clear_tick, h.config.link_recover_ms + 1);
}

TEST(SafetyLayer, SlowRoundTripsNowAndThenAreNoLinkFault) {
  // A loop or a device that woke late makes one round trip long (the device applies the newest
  // command it has, so the next is short again), and a device without an echo measures none.
  Harness h;
  h.round_trip_ms = 1.2;
  SafetyOutput out = h.settle({{3, 0, 0}, {}});
  for (int k = 0; k < 1000; ++k) {
    h.round_trip_ms = k % 4 == 0 ? 1.1 : 30;  // three in four slow, never link_timeout_ms of them on end
    out = h.tick({{3, 0, 0}, {}});
    ASSERT_FALSE(out.faults) << "tick " << k;
  }
  EXPECT_NEAR(out.wrench.force_n.x, 3.0, 1e-9);
  // Four slow on end, then no more measurements: too few to judge the link by.
  h.round_trip_ms = 1.1;
  h.tick({{3, 0, 0}, {}});
  h.round_trip_ms = 30;
  for (int k = 0; k < 4; ++k) out = h.tick({{3, 0, 0}, {}});
  h.round_trip_ms = -1;
  for (int k = 0; k < 3; ++k) out = h.tick({{3, 0, 0}, {}});
  EXPECT_FALSE(out.faults & fault_link_latency);
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

TEST(SafetyLayer, AForeignCommandLatchesZeroUntilTheOperatorResets) {
  // Someone else commanding our device (another process on the machine, another node on the
  // bus) bypasses every rule here: whoever it is, force stays off until an operator has looked.
  Harness h;
  SafetyOutput out = h.settle({{0.5, 0, 0}, {}});
  ASSERT_GT(out.wrench.force_n.x, 0.4);
  SafetyInput in;
  in.now_ns = (h.now_ns += kTickNs);
  in.command = {{0.5, 0, 0}, {}};
  in.fresh_frame = true;
  in.sim_age_ms = 0;
  in.deadman_pressed = true;
  in.foreign_command = true;
  out = h.layer.step(in);
  EXPECT_EQ(out.wrench, Wrench{}) << "zero at once, not ramped";
  EXPECT_FALSE(out.enable);
  EXPECT_TRUE(out.faults & fault_foreign_command);
  EXPECT_EQ(fault_names(out.faults & fault_foreign_command), "foreign_command") << "the cause is named";
  for (int i = 0; i < 1000; ++i) out = h.tick({{0.5, 0, 0}, {}});  // 1 s of healthy, quiet link
  EXPECT_TRUE(out.faults & fault_foreign_command) << "latched: it does not clear by itself";
  EXPECT_EQ(out.wrench, Wrench{});
  EXPECT_TRUE(h.layer.reset_estop());
  for (int i = 0; i < 300; ++i) out = h.tick({{0.5, 0, 0}, {}});
  EXPECT_FALSE(out.faults & fault_foreign_command);
  EXPECT_NEAR(out.wrench.force_n.x, 0.5, 1e-9) << "force returns through the engage gate";
}

namespace {
// One healthy tick whose command stream lost `lost` commands since the last one.
SafetyOutput tick_losing(Harness& h, std::uint32_t lost) {
  SafetyInput in;
  in.now_ns = (h.now_ns += kTickNs);
  in.command = {{0.5, 0, 0}, {}};
  in.fresh_frame = true;
  in.sim_age_ms = 0;
  in.deadman_pressed = true;
  in.commands_lost = lost;
  return h.layer.step(in);
}
}  // namespace

TEST(SafetyLayer, LosingCommandsInBulkLatchesTheCommunicationConstraintUntilTheOperatorResets) {
  // libfranka's communication_constraints_violation: a link that loses most commands renders a
  // wrench the hand never gets. Rig defaults: more than 50 lost, draining 50 per 100 ms.
  Harness h;
  SafetyOutput out = h.settle({{0.5, 0, 0}, {}});
  ASSERT_GT(out.wrench.force_n.x, 0.4);
  // losing 3 commands of every 4 (0.75 per ms against a drain of 0.5 per ms)
  int ticks = 0;
  for (; ticks < 1000 && !(out.faults & fault_communication_constraints); ++ticks)
    out = tick_losing(h, ticks % 4 != 0 ? 1 : 0);
  // the bucket fills at 0.75 - 0.5 = 0.25 per ms: 50 / 0.25 = 200 ms, to within one 4-tick period
  EXPECT_NEAR(ticks, 200, 4);
  EXPECT_EQ(out.wrench, Wrench{});
  EXPECT_FALSE(out.enable);
  EXPECT_EQ(fault_names(out.faults & fault_communication_constraints), "communication_constraints_violation");
  for (int i = 0; i < 1000; ++i) out = tick_losing(h, 0);
  EXPECT_TRUE(out.faults & fault_communication_constraints) << "latched: it does not clear by itself";
  EXPECT_TRUE(h.layer.reset_estop()) << "the explicit recovery";
  for (int i = 0; i < 300; ++i) out = tick_losing(h, 0);
  EXPECT_FALSE(out.faults & fault_communication_constraints);
  EXPECT_NEAR(out.wrench.force_n.x, 0.5, 1e-9);
}

TEST(SafetyLayer, CommandsLostWhileTheMotorsWereOffAreNoViolation) {
  // A link fault disables the device; the commands of that time are zeros that keep its motors
  // off, and a device catching up after a stall applies only the newest of them. Losing them
  // loses the hand nothing: no communication constraint, and the hand gets its wrench back.
  Harness h;
  SafetyOutput out = h.settle({{0.5, 0, 0}, {}});
  ASSERT_GT(out.wrench.force_n.x, 0.4);
  for (int i = 0; i < 10; ++i) out = h.tick({{0.5, 0, 0}, {}}, /*fresh_frame=*/false);
  ASSERT_TRUE(out.faults & fault_link_timeout);
  for (int i = 0; i < 90; ++i) out = tick_losing(h, 5);  // 450 lost, still within link_recover_ms
  EXPECT_FALSE(out.enable);
  EXPECT_FALSE(out.faults & fault_communication_constraints);
  for (int i = 0; i < 400; ++i) out = tick_losing(h, 0);
  EXPECT_FALSE(out.faults);
  EXPECT_NEAR(out.wrench.force_n.x, 0.5, 1e-9);
}

TEST(SafetyLayer, LosingCommandsNowAndThenOrInOneStallIsNoViolation) {
  // A device tick that takes two commands loses one; a 40 ms device stall supersedes 40 at once;
  // half the commands lost for a second is still within the constraint. None of these fault.
  Harness h;
  SafetyOutput out = h.settle({{0.5, 0, 0}, {}});
  out = tick_losing(h, 40);
  for (int i = 0; i < 1000; ++i) out = tick_losing(h, i % 2);
  EXPECT_FALSE(out.faults & fault_communication_constraints);
  out = tick_losing(h, 51);
  EXPECT_TRUE(out.faults & fault_communication_constraints) << "but 51 at once are more than 50";
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

// ---- Engaging under a resting load ----------------------------------------------------------------
// A hand carrying the paper's bucket (§6.4.4) holds a coupling wrench of several N for the whole
// run. After a fault the loop must give that load back to the hand, slowly, once the command is
// known to be a load and not a runaway; rig defaults: link_recover_ms 100, engage_hold_ms 150,
// engage_steady_band_n 0.5, engage_ramp_ms 200, engage_ramp_rate_n_per_s 20.

namespace {
constexpr double kEngageRateNPerTick = 20.0 * 1e-3;  // engage_ramp_rate_n_per_s * T

// Link loss of `ticks` ms under `command`; returns the last output.
SafetyOutput lose_link(Harness& h, Wrench command, int ticks = 20) {
  SafetyOutput out;
  for (int k = 0; k < ticks; ++k) out = h.tick(command, /*fresh_frame=*/false);
  return out;
}
}  // namespace

TEST(SafetyLayer, ReengagesUnderASteady5NLoadAfterALinkFaultThroughASlowRamp) {
  // Expected: the link fault clears 100 ms after frames return, the load has then been steady
  // for 150 ms at 250 ms, and the ramp to 5 N lasts max(200 ms, 5 N / 20 N/s = 250 ms): full
  // load at 500 ms. On the way it rises by at most 0.02 N per tick, so the 1 N/tick rate limit
  // never acts, and it never exceeds the load.
  Harness h;
  const Wrench load{{0, 0, -5}, {}};
  SafetyOutput out = h.settle(load);
  ASSERT_NEAR(out.wrench.force_n.z, -5.0, 1e-9);
  out = lose_link(h, load);
  ASSERT_EQ(out.wrench, Wrench{});
  int first_nonzero = -1, full = -1;
  Wrench last{};
  for (int k = 1; k <= 700; ++k) {
    out = h.tick(load);
    EXPECT_FALSE(out.flags & flag_rate_limited) << "tick " << k;
    EXPECT_LE(max_abs_change(out.wrench, last), kEngageRateNPerTick + 1e-9) << "tick " << k;
    EXPECT_LE(norm(out.wrench.force_n), 5.0 + 1e-9);
    if (first_nonzero < 0 && out.wrench != Wrench{}) first_nonzero = k;
    if (full < 0 && std::abs(out.wrench.force_n.z + 5.0) < 1e-9) full = k;
    last = out.wrench;
  }
  EXPECT_NEAR(first_nonzero, 100 + 150, 3) << "link_recover_ms + engage_hold_ms";
  EXPECT_NEAR(full, 100 + 150 + 250, 4) << "+ a ramp of 5 N / 20 N/s";
  EXPECT_EQ(out.faults, 0u);
}

TEST(SafetyLayer, AHeldLoadWithHandTremorStillCountsAsSteady) {
  // A real hand is not a clamp: physiological tremor (8-12 Hz) moves a 1000 N/m coupling spring
  // by a few tenths of a newton. 5 N +/- 0.3 N at 9 Hz stays within the 0.5 N band.
  Harness h;
  auto held = [&](int k) { return Wrench{{5.0 + 0.3 * std::sin(2 * M_PI * 9.0 * k * 1e-3), 0, 0}, {}}; };
  int k = 0;
  SafetyOutput out;
  for (; k < 150; ++k) out = h.tick({});
  for (; k < 400; ++k) out = h.tick(held(k));  // first engagement (small start), now carrying 5 N
  lose_link(h, held(k));
  int first_nonzero = -1;
  for (int j = 1; j <= 800; ++j, ++k) {
    out = h.tick(held(k));
    if (first_nonzero < 0 && out.wrench != Wrench{}) first_nonzero = j;
  }
  EXPECT_NEAR(first_nonzero, 250, 3);
  EXPECT_NEAR(out.wrench.force_n.x, held(k - 1).force_n.x, 0.05) << "following the load again";
}

TEST(SafetyLayer, ALargeOscillatingOrDriftingCommandKeepsWaiting) {
  // After a sim restart with the hand far from x0, the coupling spring can ring: 5 N +/- 3 N at
  // 2 Hz. Or a hostile sim drifts 4 N/s (0.6 N per 150 ms window). Neither is a resting load: the
  // output stays exactly zero for 3 s, flagged waiting_to_engage.
  for (int variant = 0; variant < 2; ++variant) {
    Harness h;
    h.settle({{5, 0, 0}, {}});
    lose_link(h, {{5, 0, 0}, {}});
    for (int k = 0; k < 3000; ++k) {
      double t = k * 1e-3;
      double fx = variant == 0 ? 5.0 + 3.0 * std::sin(2 * M_PI * 2.0 * t) : 2.0 + 4.0 * std::fmod(t, 1.5);
      SafetyOutput out = h.tick({{fx, 0, 0}, {}});
      ASSERT_EQ(out.wrench, Wrench{}) << "variant " << variant << " tick " << k;
      if (k > 100) {
        ASSERT_TRUE(out.flags & flag_waiting_to_engage);
      }
    }
  }
}

TEST(SafetyLayer, ASteadyLoadBeyondTheLimitsEngagesAtTheLimitThroughTheSlowRamp) {
  // A pan held by its handle asks ~0.9 N*m of a 0.5 N*m device, a jammed body (or a hostile
  // writer) a steady 15 N of a 10 N device. An engaged device renders such loads at the limit;
  // after a fault it must get there again, not stay at zero for the rest of the run. Expected,
  // judged on the limited command: link recovery 100 ms + hold 150 ms, then a ramp of
  // max(200 ms, 10 N / 20 N/s, 0.5 N*m / 1 N*m/s) = 500 ms; never beyond a limit on the way.
  Harness h;
  const Wrench ask{{15, 0, 0}, {0, 0.9, 0}};
  h.settle(ask);
  lose_link(h, ask);
  SafetyOutput out;
  int first_nonzero = -1;
  for (int k = 1; k <= 1000; ++k) {
    out = h.tick(ask);
    ASSERT_LE(norm(out.wrench.force_n), h.config.max_force_n + 1e-9) << "tick " << k;
    ASSERT_LE(norm(out.wrench.torque_nm), h.config.max_torque_nm + 1e-9) << "tick " << k;
    if (first_nonzero < 0 && out.wrench != Wrench{}) first_nonzero = k;
  }
  EXPECT_NEAR(first_nonzero, 100 + 150, 3);
  EXPECT_NEAR(out.wrench.force_n.x, h.config.max_force_n, 1e-9);
  EXPECT_NEAR(out.wrench.torque_nm.y, h.config.max_torque_nm, 1e-9);
  EXPECT_FALSE(out.flags & flag_waiting_to_engage);
  // A non-finite command never counts as steady, however long it lasts.
  Harness nan_sim;
  nan_sim.settle({});
  lose_link(nan_sim, {{std::nan(""), 0, 0}, {}});
  for (int k = 0; k < 1000; ++k) out = nan_sim.tick({{std::nan(""), 0, 0}, {}});
  EXPECT_EQ(out.wrench, Wrench{});
}

TEST(SafetyLayer, ASteadyCommandDoesNotEngageWhileADeadmanEstopOrLinkGateHolds) {
  // Steadiness is only counted with every gate open: a released deadman, a latched e-stop or a
  // dead link keep the output exactly zero however long the load is steady, and the 150 ms hold
  // window starts when the gate opens (a load seen through a stale device pose proves nothing).
  const Wrench load{{5, 0, 0}, {}};
  SafetyConfig c;
  c.require_deadman = true;
  for (int gate = 0; gate < 3; ++gate) {
    Harness h(c);
    h.settle(load);
    h.deadman = gate != 0;
    h.estop = gate == 1;
    SafetyOutput out;
    for (int k = 0; k < 1000; ++k) {
      out = h.tick(load, /*fresh_frame=*/gate != 2);
      if (gate == 2 && k < 6) continue;  // link_timeout_ms (5 ms) + 1 tick to notice
      ASSERT_EQ(out.wrench, Wrench{}) << "gate " << gate << " tick " << k;
      ASSERT_TRUE(out.flags & flag_hard_zero);
    }
    h.deadman = true;
    h.estop = false;
    if (gate == 1) {
      h.tick(load);  // the layer sees the button released
      ASSERT_TRUE(h.layer.reset_estop());
    }
    int first_nonzero = -1;
    for (int k = 1; k <= 600 && first_nonzero < 0; ++k)
      if (h.tick(load).wrench != Wrench{}) first_nonzero = k;
    int after_release_ms = gate == 2 ? 100 : gate == 1 ? -1 : 0;  // link recovery; the e-stop's extra tick
    EXPECT_NEAR(first_nonzero, after_release_ms + 150, 3) << "gate " << gate;
  }
}

TEST(SafetyLayer, ARestartedSimMustPassTheEngageGate) {
  // A crashed sim restarted with its body elsewhere: its spring rings about 5 N (1-9 N at 3 Hz),
  // or through zero (+/- 6 N at 3 Hz: below 1 N for ~18 ms per crossing, under engage_small_ms).
  // Its state is new, so it must not fade in on the step-4 ramp as a stalled sim does; it waits,
  // then engages once steady. When the old sim's wrench had not yet faded out (3.5 N here), it
  // drops to zero at the rate limit (1 N per tick).
  Harness h;
  h.settle({{5, 0, 0}, {}});
  for (int k = 0; k < 80; ++k) h.tick({{5, 0, 0}, {}}, true, /*sim_fresh=*/false);  // stale, fading
  h.sim_restarted = true;
  SafetyOutput out;
  for (int k = 0; k < 2000; ++k) {
    double ringing = k < 1000 ? 5.0 + 4.0 * std::sin(2 * M_PI * 3.0 * k * 1e-3) : 6.0 * std::sin(2 * M_PI * 3.0 * k * 1e-3);
    out = h.tick({{ringing, 0, 0}, {}});
    if (k >= 4) {
      ASSERT_EQ(out.wrench, Wrench{}) << "tick " << k;
    } else {
      ASSERT_NEAR(out.wrench.force_n.x, std::max(0.0, 2.5 - k), 1e-6) << "tick " << k;
    }
  }
  for (int k = 0; k < 600; ++k) out = h.tick({{4, 0, 0}, {}});
  EXPECT_NEAR(out.wrench.force_n.x, 4.0, 1e-9);
}

TEST(SafetyLayer, PiecewiseSteadyLargeCommandsWithGateFlickerNeverExceedALimit) {
  // The steady rule engages on large commands, so the property test is repeated on streams made
  // of random holds (10-800 ms at up to 7 N / 0.35 N*m per axis) with link drops, deadman flicker and sim
  // stalls: every output within every limit; every step within the rate limit unless a hard zero.
  SafetyConfig config;
  config.require_deadman = true;
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(-1, 1);
    std::uniform_int_distribution<int> hold_ticks(10, 800);
    std::bernoulli_distribution drop(0.0005), release(0.0005), stall(0.0005);
    Harness h(config);
    Wrench previous{}, command{};
    int left = 0, stalled = 0, released = 0, engaged_ticks = 0;
    for (int k = 0; k < 6000; ++k) {
      if (--left <= 0) {
        command = {{7 * u(rng), 7 * u(rng), 7 * u(rng)}, {0.35 * u(rng), 0.35 * u(rng), 0.35 * u(rng)}};
        left = hold_ticks(rng);
      }
      if (stall(rng)) stalled = 200;
      if (release(rng)) released = 50;
      h.deadman = released-- <= 0;
      SafetyOutput out = h.tick(command, !drop(rng), stalled-- <= 0);
      ASSERT_TRUE(within_limits(out.wrench, config, 1e-9)) << "seed " << seed << " tick " << k;
      if (!(out.wrench == Wrench{} && (out.flags & flag_hard_zero))) {
        ASSERT_LE(norm(out.wrench.force_n - previous.force_n), 1.0 * (1 + 1e-9)) << "seed " << seed << " tick " << k;
        ASSERT_LE(norm(out.wrench.torque_nm - previous.torque_nm), 0.05 * (1 + 1e-9));
      }
      engaged_ticks += norm(out.wrench.force_n) > 1.0;
      previous = out.wrench;
    }
    EXPECT_GT(engaged_ticks, 300) << "seed " << seed << ": the stream must exercise steady engagement";
  }
}

TEST(SafetyLayer, EngageSettingsComeFromTheRigWithTorqueCounterpartsDerived) {
  hapfluid::config::RigDevice device;
  device.limits.max_force_n = 8.0;
  device.limits.max_torque_nm = 0.4;
  device.watchdogs.engage_hold_ms = 120;
  device.watchdogs.engage_steady_band_n = 0.4;
  device.watchdogs.engage_ramp_rate_n_per_s = 10;
  SafetyConfig c = make_safety_config(device, 1'000'000);
  EXPECT_EQ(c.engage_hold_ms, 120);
  EXPECT_DOUBLE_EQ(c.engage_steady_band_nm, 0.4 * 0.4 / 8.0);
  EXPECT_DOUBLE_EQ(c.engage_ramp_rate_nm_per_s, 10 * 0.4 / 8.0);
  EXPECT_NE(describe(c).find("engage_hold_ms = 120"), std::string::npos);
}

TEST(SafetyLayer, AZeroHoldWindowKeepsTheSmallCommandRuleOnly) {
  // engage_hold_ms = 0 is the gate without a hold window, for a rig whose operator wants it.
  SafetyConfig c;
  c.engage_hold_ms = 0;
  Harness h(c);
  h.settle({});
  lose_link(h, {{5, 0, 0}, {}});
  SafetyOutput out;
  for (int k = 0; k < 1000; ++k) out = h.tick({{5, 0, 0}, {}});
  EXPECT_EQ(out.wrench, Wrench{});
}

TEST(SafetyLayer, ARigWhoseEngageRampIsFasterThanItsRateLimitIsRefusedByName) {
  // An engage ramp faster than max_force_rate_n_per_s would be shaped by the rate limiter, the
  // last line of defence, instead of by design: the rig file is refused, naming the key.
  std::ifstream in(std::string(HAPFLUID_SOURCE_DIR) + "/tests/rt_core/rigs/one_arm.toml");
  std::stringstream text;
  text << in.rdbuf();
  std::string rig = text.str();
  rig.insert(rig.find("[devices.transport]"), "max_force_rate_n_per_s = 100.0\nengage_ramp_rate_n_per_s = 150.0\n");
  auto path = std::filesystem::temp_directory_path() / ("engage-rate-" + std::to_string(::getpid()) + ".toml");
  std::ofstream(path) << rig;
  try {
    hapfluid::config::load_rig(path);
    ADD_FAILURE() << "accepted an engage ramp faster than the rate limit";
  } catch (const hapfluid::config::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("engage_ramp_rate_n_per_s"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("max_force_rate_n_per_s"), std::string::npos) << e.what();
  }
  std::filesystem::remove(path);
}
