// The loop's answer to device-reported faults: a latched command-watchdog trip (the device's
// reaction to the host's own silence, e.g. a link loss longer than device_watchdog_ms) is cleared
// once frames flow again, always with enable off; every other fault stays latched.
#include <gtest/gtest.h>

#include "hapfluid/config/rig.hpp"
#include "hapfluid/rt/loop.hpp"
#include "hapfluid/wire/codec.h"
#include "loop_test_rig.hpp"

using namespace hapfluid;

namespace {

// The device boundary: answers every poll with a fresh, valid state carrying `fault` (or nothing
// when `silent`), and keeps the last command the loop sent.
class FaultyDevice final : public device::Device {
 public:
  std::uint32_t fault = 0;
  std::uint32_t restarts = 0;  // health().device_restarts
  std::uint64_t foreign = 0;   // health().foreign_commands
  std::uint64_t lost = 0;      // health().commands_lost
  bool echoes = false;         // health().echoes_commands: its states echo the commands it took
  bool deaf = false;           // ... and it has stopped taking them
  std::uint64_t sent = 0, heard = 0;
  std::uint64_t round_trip_ns = 0;  // > 0: each command heard is echoed this long after its send
  std::uint64_t round_trips = 0;
  bool silent = false;
  device::DeviceCommand last{};
  bool poll(device::DeviceState& out) override {
    if (silent) return false;
    out = {};
    out.host_receive_ns = shm::monotonic_ns();
    out.fault = fault;
    if (echoes && !deaf && round_trip_ns && sent) ++round_trips;  // this state echoes the newest command
    return true;
  }
  bool send(const device::DeviceCommand& c) override {
    last = c;
    ++sent;
    if (!deaf) heard = sent;
    return true;
  }
  device::DeviceHealth health() const override {
    device::DeviceHealth h;
    h.connected = true;
    h.device_restarts = restarts;
    h.foreign_commands = foreign;
    h.commands_lost = lost;
    h.echoes_commands = echoes;
    h.commands_sent = sent;
    h.commands_sent_when_heard = heard;
    h.echo_round_trip_ns = round_trip_ns;
    h.echo_round_trips = round_trips;
    return h;
  }
  const char* name() const override { return "faulty"; }
};

struct LoopWithOneDevice {
  FaultyDevice* device = nullptr;
  std::unique_ptr<rt::RtLoop> loop;
  std::uint64_t now = 1'000'000'000;
  LoopWithOneDevice() {
    config::Rig rig = rt_test::one_device_rig("arm", "device-faults-test");
    auto d = std::make_unique<FaultyDevice>();
    device = d.get();
    std::vector<std::unique_ptr<device::Device>> devices;
    devices.push_back(std::move(d));
    rt::LoopOptions options;
    options.publish_trace = false;
    loop = std::make_unique<rt::RtLoop>(rig, std::move(devices), options);
  }
  void ticks(int n) {
    for (int i = 0; i < n; ++i, now += 1'000'000) loop->tick(now, now);
  }
  // The safety layer's link recovery and engage gate run on the real clock: tick until `done`
  // holds, 2 s of real time at most; true when it did.
  template <class Done>
  bool tick_until(Done done) {
    const std::uint64_t deadline = shm::monotonic_ns() + 2'000'000'000ull;
    while (!done()) {
      if (shm::monotonic_ns() > deadline) return false;
      ticks(1);
    }
    return true;
  }
};

}  // namespace

TEST(LoopDeviceFaults, ALatchedCommandWatchdogTripIsClearedWhileDisabledOnceFramesReturn) {
  LoopWithOneDevice l;
  l.device->fault = HF_FAULT_COMMAND_WATCHDOG;
  l.ticks(3);
  EXPECT_TRUE(l.device->last.clear_faults);
  EXPECT_FALSE(l.device->last.enable) << "the device honours a clear only while disabled";
  l.device->fault = 0;
  l.ticks(1);
  EXPECT_FALSE(l.device->last.clear_faults) << "nothing left to clear";
}

TEST(LoopDeviceFaults, EveryOtherDeviceFaultStaysLatched) {
  // An e-stop, an over-current or a workspace fault is the device protecting the hand for its own
  // reasons: only an operator may clear those.
  for (std::uint32_t fault : {std::uint32_t(HF_FAULT_ESTOP), std::uint32_t(HF_FAULT_COMMAND_WATCHDOG | HF_FAULT_ESTOP),
                              std::uint32_t(HF_FAULT_OVERCURRENT), std::uint32_t(HF_FAULT_WORKSPACE)}) {
    LoopWithOneDevice l;
    l.device->fault = fault;
    l.ticks(3);
    EXPECT_FALSE(l.device->last.clear_faults) << "fault bits " << fault;
    EXPECT_FALSE(l.device->last.enable);
  }
}

TEST(LoopDeviceFaults, NoClearWithoutAFreshFrame) {
  // The clear is an answer to what the device says now, not to a state remembered from before a
  // link loss.
  LoopWithOneDevice l;
  l.device->fault = HF_FAULT_COMMAND_WATCHDOG;
  l.ticks(2);
  l.device->silent = true;
  l.ticks(1);
  EXPECT_FALSE(l.device->last.clear_faults);
}

TEST(LoopDeviceFaults, ADeviceThatRebootedIsTakenUpThroughLinkRecovery) {
  // A rebooted device forgot the command it applied and starts from its own state: however short
  // its silence, the loop zeroes the wrench at once and gives it back only after the link was
  // healthy for link_recover_ms (100 ms; the loop's clock is CLOCK_MONOTONIC), as after any link loss.
  LoopWithOneDevice l;
  auto link_invalid = [&] { return (l.loop->last_trace().devices[0].faults & safety::fault_link_invalid) != 0; };
  l.ticks(3);
  ASSERT_FALSE(link_invalid());
  l.device->restarts = 1;
  const std::uint64_t restart_ns = shm::monotonic_ns();
  l.ticks(1);
  EXPECT_TRUE(link_invalid()) << "the restart was not taken as a link loss";
  EXPECT_FALSE(l.device->last.enable);
  while (link_invalid() && shm::monotonic_ns() - restart_ns < 2'000'000'000ull) {
    l.ticks(1);
    if (link_invalid()) {
      EXPECT_FALSE(l.device->last.enable);
    }
  }
  EXPECT_FALSE(link_invalid()) << "never recovered";
  EXPECT_GE(double(shm::monotonic_ns() - restart_ns) * 1e-6, 100.0) << "recovered before link_recover_ms";
}

TEST(LoopDeviceFaults, AForeignCommandLatchesTheDeviceAtZeroUntilTheOperatorResets) {
  // The driver heard a command for our device that we did not send: the loop zeroes and disables
  // that device at once, names the cause (foreign_command, in the trace and the flight recorder's
  // file name) and keeps it so until the operator's reset (SIGUSR2).
  LoopWithOneDevice l;
  auto foreign = [&] { return (l.loop->last_trace().devices[0].faults & safety::fault_foreign_command) != 0; };
  l.ticks(3);
  ASSERT_FALSE(foreign());
  l.device->foreign = 1;
  l.ticks(1);
  EXPECT_TRUE(foreign());
  EXPECT_FALSE(l.device->last.enable);
  EXPECT_EQ(l.device->last.force_n[0], 0.0);
  l.ticks(200);
  EXPECT_TRUE(foreign()) << "cleared without the operator";
  l.loop->request_estop_reset();
  l.ticks(1);
  EXPECT_FALSE(foreign());
}

TEST(LoopDeviceFaults, CommandsTheDeviceNeverAppliedCountTowardTheCommunicationConstraint) {
  // The driver counts the commands the device's echo skipped; the loop hands each tick's new
  // ones to the safety layer, which latches the fault beyond 50 (rig default) until the reset.
  // Only commands that enabled the motors count: the device is engaged first (the loop's link
  // recovery runs on the real clock: tick_until it enables).
  LoopWithOneDevice l;
  auto violated = [&] {
    return (l.loop->last_trace().devices[0].faults & safety::fault_communication_constraints) != 0;
  };
  l.tick_until([&] { return l.device->last.enable; });
  ASSERT_TRUE(l.device->last.enable) << safety::fault_names(l.loop->last_trace().devices[0].faults);
  ASSERT_FALSE(violated());
  l.device->lost += 30;
  l.ticks(1);
  EXPECT_FALSE(violated());
  l.device->lost += 30;  // 60 within 1 ms of loop ticks
  l.ticks(1);
  EXPECT_TRUE(violated());
  EXPECT_FALSE(l.device->last.enable);
  l.ticks(100);
  EXPECT_TRUE(violated()) << "cleared without the operator";
}

TEST(LoopDeviceFaults, ADeviceThatKeepsTalkingButStopsHearingUsIsALinkFaultUntilItHearsAgain) {
  // Its states keep coming, fresh and valid, but their echo no longer follows our commands.
  // Once it has missed device_watchdog_ms of them (20 at 1 kHz) the loop disables it and says
  // why; when it hears again the link recovers as after any link fault, through the engage
  // ramp. (Engaged first on the real clock, as above.)
  LoopWithOneDevice l;
  l.device->echoes = true;
  auto not_listening = [&] {
    return (l.loop->last_trace().devices[0].faults & safety::fault_device_not_listening) != 0;
  };
  l.tick_until([&] { return l.device->last.enable; });
  ASSERT_TRUE(l.device->last.enable) << safety::fault_names(l.loop->last_trace().devices[0].faults);
  l.device->deaf = true;
  l.ticks(20);
  EXPECT_FALSE(not_listening()) << "20 commands unheard are within the device's own watchdog";
  EXPECT_TRUE(l.device->last.enable);
  l.ticks(2);
  EXPECT_TRUE(not_listening());
  EXPECT_FALSE(l.device->last.enable);
  EXPECT_EQ(safety::fault_names(l.loop->last_trace().devices[0].faults & safety::fault_device_not_listening),
            "device_not_listening");
  l.device->deaf = false;  // it hears again
  EXPECT_TRUE(l.tick_until([&] { return !not_listening(); })) << "a link fault recovers once the device listens again";
}

TEST(LoopDeviceFaults, ADeviceWhoseEchoComesBackLateIsALinkFaultUntilItComesBackInTime) {
  // Fresh states every tick, each echoing a command sent 25 ms before (a delay on the link):
  // the loop hands each round trip to the safety layer, which disables the device and says why,
  // and the loop's link report keeps the longest. (Engaged first on the real clock, as above.)
  LoopWithOneDevice l;
  l.device->echoes = true;
  l.device->round_trip_ns = 1'000'000;
  auto latency = [&] { return (l.loop->last_trace().devices[0].faults & safety::fault_link_latency) != 0; };
  l.tick_until([&] { return l.device->last.enable; });
  ASSERT_TRUE(l.device->last.enable) << safety::fault_names(l.loop->last_trace().devices[0].faults);
  EXPECT_FALSE(latency());
  l.device->round_trip_ns = 25'000'000;
  EXPECT_TRUE(l.tick_until(latency));
  EXPECT_FALSE(l.device->last.enable);
  EXPECT_EQ(l.loop->link_quality(0).round_trip_ms, 25.0);
  EXPECT_EQ(l.loop->link_quality(0).longest_round_trip_ms, 25.0);
  EXPECT_EQ(l.loop->link_quality(0).round_trips, l.device->round_trips);
  l.device->round_trip_ns = 1'000'000;
  EXPECT_TRUE(l.tick_until([&] { return !latency(); })) << "a link fault recovers once the echo is back in time";
}

TEST(LoopDeviceFaults, ADeviceWithoutACommandEchoIsNeverJudgedDeaf) {
  // A device kind whose states carry no echo (echoes_commands false) says nothing about it.
  LoopWithOneDevice l;
  l.device->deaf = true;
  l.ticks(200);
  EXPECT_EQ(l.loop->last_trace().devices[0].faults & safety::fault_device_not_listening, 0u);
}

TEST(LoopDeviceFaults, CountsTheDriverMadeBeforeTheLoopStartedAreNotThisRunsButForeignCommandsAre) {
  // Commands lost or a restart seen before the loop (another program drove the device) say
  // nothing about this run; a foreign command heard while opening the device is someone else
  // commanding it now.
  auto device = std::make_unique<FaultyDevice>();
  device->lost = 1000;
  device->restarts = 2;
  device->foreign = 1;
  std::vector<std::unique_ptr<device::Device>> devices;
  devices.push_back(std::move(device));
  rt::LoopOptions options;
  options.publish_trace = false;
  rt::RtLoop loop(rt_test::one_device_rig("arm", "device-faults-before"), std::move(devices), options);
  loop.tick(1'000'000'000, 1'000'000'000);
  const std::uint32_t faults = loop.last_trace().devices[0].faults;
  EXPECT_EQ(faults & (safety::fault_communication_constraints | safety::fault_link_invalid), 0u);
  EXPECT_NE(faults & safety::fault_foreign_command, 0u);
}
