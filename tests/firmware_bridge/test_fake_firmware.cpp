// The emulated firmware's safety rules, tick by tick (no processes, no clock): these are the
// rules a real arm must follow so a crashed host can never leave force on a hand.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>

#include "fake_firmware.hpp"

namespace {

using hapfluid::fake::DeviceModel;
using hapfluid::fake::FakeFirmware;

constexpr double kTick = 1e-3;

hf_message command(std::uint16_t seq, double fx, std::uint8_t flags) {
  hf_message m;
  std::memset(&m, 0, sizeof m);
  m.type = HF_MSG_COMMAND;
  m.seq = seq;
  m.body.command.force_n[0] = fx;
  m.body.command.flags = flags;
  return m;
}

hapfluid::config::PoseTwist still_hand() { return {}; }

// The rules other than the rate limit, each seen in one tick: a model whose motors follow a step.
DeviceModel without_rate_limit() {
  DeviceModel model;
  model.max_force_rate_n_per_s = 1e9;
  model.max_torque_rate_nm_per_s = 1e9;
  return model;
}

TEST(FakeFirmware, WatchdogCutsTheMotorsOnTheFirstTickThatCompletesItsSilenceLimit) {
  DeviceModel model = without_rate_limit();
  model.watchdog_ms = 20;
  FakeFirmware fw(model, {});
  double t = 0;
  std::uint16_t seq = 0;
  for (; t < 0.1; t += kTick) {  // 100 ms of a healthy 1 kHz command stream pushing 3 N
    fw.receive(command(seq++, 3.0, HF_CMD_ENABLE), t);
    fw.step(t, kTick, still_hand());
    ASSERT_EQ(fw.record().applied_force_n[0], 3.0);
  }
  const double last_command = t - kTick;
  double tripped_at = -1;
  for (; t < 0.2; t += kTick) {  // the host falls silent
    fw.step(t, kTick, still_hand());
    if (fw.record().applied_force_n[0] == 0 && tripped_at < 0) tripped_at = t;
  }
  // zero torque on the first tick at which 20 ms have passed without a command
  EXPECT_NEAR((tripped_at - last_command) * 1e3, 20.0, 1e-6);
  EXPECT_TRUE(fw.faults() & HF_FAULT_COMMAND_WATCHDOG);
  EXPECT_TRUE(fw.status() & HF_STATUS_WATCHDOG_TRIPPED);
  EXPECT_TRUE(fw.take_new_fault()) << "a new fault is reported at once";
  EXPECT_FALSE(fw.take_new_fault());
}

TEST(FakeFirmware, AWatchdogFaultStaysLatchedWhenCommandsReturnUntilExplicitlyCleared) {
  FakeFirmware fw(DeviceModel{}, {});
  fw.receive(command(0, 2.0, HF_CMD_ENABLE), 0);
  for (double t = 0; t < 0.05; t += kTick) fw.step(t, kTick, still_hand());
  ASSERT_TRUE(fw.faults() & HF_FAULT_COMMAND_WATCHDOG);
  // the host comes back still asking for force: it must not get it back silently
  fw.receive(command(1, 2.0, HF_CMD_ENABLE), 0.05);
  fw.step(0.05, kTick, still_hand());
  EXPECT_EQ(fw.record().applied_force_n[0], 0.0);
  // a clear request together with enable is refused: clearing must never switch force on
  fw.receive(command(2, 2.0, HF_CMD_ENABLE | HF_CMD_CLEAR_FAULTS), 0.051);
  fw.step(0.051, kTick, still_hand());
  EXPECT_NE(fw.faults(), 0);
  fw.receive(command(3, 0.0, HF_CMD_CLEAR_FAULTS), 0.052);
  fw.step(0.052, kTick, still_hand());
  EXPECT_EQ(fw.faults(), 0);
  fw.receive(command(4, 2.0, HF_CMD_ENABLE), 0.053);
  fw.step(0.053, kTick, still_hand());
  EXPECT_EQ(fw.record().applied_force_n[0], 2.0);
}

TEST(FakeFirmware, EmergencyStopLatchesFromEitherTheMessageOrTheCommandFlag) {
  for (bool by_message : {true, false}) {
    FakeFirmware fw(DeviceModel{}, {});
    fw.receive(command(0, 1.0, HF_CMD_ENABLE), 0);
    if (by_message) {
      hf_message e;
      std::memset(&e, 0, sizeof e);
      e.type = HF_MSG_ESTOP;
      fw.receive(e, 0.001);
    } else {
      fw.receive(command(1, 1.0, HF_CMD_ENABLE | HF_CMD_ESTOP), 0.001);
    }
    fw.receive(command(2, 1.0, HF_CMD_ENABLE), 0.002);
    fw.step(0.002, kTick, still_hand());
    EXPECT_EQ(fw.record().applied_force_n[0], 0.0);
    EXPECT_TRUE(fw.status() & HF_STATUS_ESTOP_LATCHED);
  }
}

TEST(FakeFirmware, MotorForceIsLimitedInNormWithItsDirectionKept) {
  DeviceModel model = without_rate_limit();
  model.max_force_n = 5.0;
  FakeFirmware fw(model, {});
  hf_message m = command(0, 6.0, HF_CMD_ENABLE);
  m.body.command.force_n[1] = 8.0;  // |(6, 8)| = 10 N, twice the motor limit
  fw.receive(m, 0);
  fw.step(0, kTick, still_hand());
  EXPECT_NEAR(fw.record().applied_force_n[0], 3.0, 1e-12);
  EXPECT_NEAR(fw.record().applied_force_n[1], 4.0, 1e-12);
  EXPECT_TRUE(fw.status() & HF_STATUS_FORCE_SATURATED);
}

TEST(FakeFirmware, MotorForceRisesNoFasterThanTheDevicesOwnRateLimitButDropsToZeroAtOnce) {
  // A command stepping 0 -> 10 N (a sender that bypassed the host's safety layer, which never
  // steps like this) reaches the hand at 2000 N/s: 2 N per 1 ms tick, 10 N after 5 ticks. Motors
  // off is the safe step and is taken at once.
  DeviceModel model;
  model.max_force_rate_n_per_s = 2000.0;
  FakeFirmware fw(model, {});
  double t = 0;
  std::uint16_t seq = 0;
  for (int tick = 1; tick <= 6; ++tick, t += kTick) {
    fw.receive(command(seq++, 10.0, HF_CMD_ENABLE), t);
    fw.step(t, kTick, still_hand());
    EXPECT_NEAR(fw.record().applied_force_n[0], std::min(10.0, 2.0 * tick), 1e-9) << "tick " << tick;
  }
  fw.receive(command(seq++, -10.0, HF_CMD_ENABLE), t);  // reversing is a 20 N change: 2 N per tick too
  fw.step(t, kTick, still_hand());
  t += kTick;
  EXPECT_NEAR(fw.record().applied_force_n[0], 8.0, 1e-9);
  fw.receive(command(seq++, -10.0, 0), t);  // disabled
  fw.step(t, kTick, still_hand());
  EXPECT_EQ(fw.record().applied_force_n[0], 0.0) << "motors off at once, not ramped";
}

TEST(FakeFirmware, AConstantForceDisplacesTheHeldHandleByForceOverHandStiffness) {
  DeviceModel model;
  FakeFirmware fw(model, {});
  double t = 0;
  for (std::uint16_t seq = 0; t < 2.0; t += kTick, ++seq) {
    fw.receive(command(seq, 2.0, HF_CMD_ENABLE), t);
    fw.step(t, kTick, still_hand());
  }
  // static equilibrium: F_motor = K_hand * x  ->  2 N / 400 N/m = 5 mm
  EXPECT_NEAR(fw.state(0).position_m[0], 2.0 / model.hand_stiffness_n_per_m, 1e-4);
}

TEST(FakeFirmware, TheWorkspaceWallStopsTheHandle) {
  DeviceModel model;
  model.workspace_half_extent_m = 0.01;
  model.max_force_n = 12.0;
  FakeFirmware fw(model, {});
  double t = 0;
  for (std::uint16_t seq = 0; t < 0.5; t += kTick, ++seq) {
    fw.receive(command(seq, 10.0, HF_CMD_ENABLE), t);  // would push 25 mm into a 10 mm box
    fw.step(t, kTick, still_hand());
  }
  EXPECT_DOUBLE_EQ(fw.state(0).position_m[0], 0.01);
  EXPECT_TRUE(fw.status() & HF_STATUS_AT_WORKSPACE_LIMIT);
}

TEST(FakeFirmware, ARestartedHostIsAcceptedAfterASilenceButLateFramesAreNot) {
  FakeFirmware fw(DeviceModel{}, {});
  fw.receive(command(500, 1.0, 0), 0.0);
  fw.receive(command(501, 1.0, 0), 0.001);
  fw.receive(command(499, 9.0, 0), 0.002);  // a late duplicate inside a live stream
  fw.step(0.002, kTick, still_hand());
  EXPECT_EQ(fw.record().command.force_n[0], 1.0);
  fw.receive(command(0, 4.0, 0), 0.5);  // host restarted, counts from 0 again
  fw.step(0.5, kTick, still_hand());
  EXPECT_EQ(fw.record().command.force_n[0], 4.0);
}

}  // namespace
