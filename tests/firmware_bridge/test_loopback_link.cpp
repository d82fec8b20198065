// Driver logic end to end in one process: a HapticArm on the host side of a loopback bus and
// the emulated firmware on the device side, stepped tick by tick, on every framing. The same
// code runs against real buses; here nothing depends on kernel drivers or wall-clock timing.
#include <gtest/gtest.h>
#include <linux/can.h>
#include <linux/can/error.h>
#include <unistd.h>

#include <cstring>
#include <memory>
#include <string>

#include "fake_firmware.hpp"
#include "hapfluid/device/haptic_arm.hpp"
#include "hapfluid/device/loopback.hpp"
#include "hapfluid/device/open_device.hpp"

namespace {

using namespace hapfluid;
using device::Framing;

std::string socket_path(const char* tag) {
  return "/tmp/hapfluid-test-" + std::string(tag) + "-" + std::to_string(::getpid()) + ".sock";
}

device::LoopbackFormat format(Framing f) {
  return f == Framing::hid ? device::LoopbackFormat::hid
         : f == Framing::bulk ? device::LoopbackFormat::bulk : device::LoopbackFormat::can;
}

// Device side (bus) and host side (driver) of one loopback link.
struct Rig {
  explicit Rig(Framing framing, const char* tag) : path(socket_path(tag)) {
    device_link = std::make_unique<device::MessageLink>(
        std::make_unique<device::LoopbackTransport>(path, device::LoopbackRole::bus, format(framing)), framing, 3,
        device::Side::device);
    auto host_link = std::make_unique<device::MessageLink>(
        std::make_unique<device::LoopbackTransport>(path, device::LoopbackRole::peer, format(framing)), framing, 3,
        device::Side::host);
    arm = std::make_unique<device::HapticArm>("test", std::move(host_link), 0);
    firmware = std::make_unique<fake::FakeFirmware>(fake::DeviceModel{}, config::Pose{},
                                                    device_link->sequence_modulus());
  }
  // One 1 ms tick of the device: receive, step, send a state (unless told to drop it).
  void device_tick(bool send_state = true, bool corrupt = false, bool send_fault = true) {
    hf_message m;
    firmware->begin_tick();
    for (int budget = device::kDrainUnitBudget; device_link->receive(m, budget) == device::Io::ok;)
      firmware->receive(m, t);
    firmware->reject_frames(static_cast<std::uint32_t>(device_link->frames_bad() - frames_bad_seen), t);
    frames_bad_seen = device_link->frames_bad();
    firmware->step(t, 1e-3, config::PoseTwist{});
    if (firmware->take_new_fault() && send_fault) {
      std::memset(&m, 0, sizeof m);
      m.type = HF_MSG_FAULT;
      m.body.fault = firmware->fault_report(t);
      device_link->send(m);
    }
    std::memset(&m, 0, sizeof m);
    m.type = HF_MSG_STATE;
    m.seq = state_seq++;
    m.body.state = firmware->state(static_cast<std::uint32_t>(t * 1e6));
    if (corrupt) device_link->corrupt_next(1);
    if (send_state) device_link->send(m);
    t += 1e-3;
  }
  std::string path;
  std::unique_ptr<device::MessageLink> device_link;
  std::unique_ptr<device::HapticArm> arm;
  std::unique_ptr<fake::FakeFirmware> firmware;
  double t = 0;
  std::uint16_t state_seq = 0;
  std::uint64_t frames_bad_seen = 0;
};

class EveryFraming : public ::testing::TestWithParam<Framing> {};

TEST_P(EveryFraming, CommandsReachTheFirmwareAndStatesComeBackWithTheirEcho) {
  Rig rig(GetParam(), device::to_string(GetParam()));
  device::DeviceState state;
  device::DeviceCommand c;
  c.force_n[0] = 1.5;
  c.torque_nm[2] = -0.05;
  c.enable = true;
  for (int tick = 0; tick < 300; ++tick) {
    ASSERT_TRUE(rig.arm->send(c));
    rig.device_tick();
    ASSERT_TRUE(rig.arm->poll(state)) << "tick " << tick;
  }
  EXPECT_EQ(rig.firmware->record().command.force_n[0], 1.5);
  EXPECT_NEAR(rig.firmware->record().applied_torque_nm[2], -0.05, 1e-12);
  EXPECT_EQ(state.command_echo, rig.arm->health().last_command_sequence & 0xFF);
  EXPECT_TRUE(state.status & HF_STATUS_MOTORS_ENABLED);
  EXPECT_GT(state.position_m[0], 0.0) << "1.5 N pushes the handle along +x";
  auto h = rig.arm->health();
  EXPECT_EQ(h.frames_bad, 0u);
  EXPECT_EQ(h.sequence_gaps, 0u);
  EXPECT_EQ(h.commands_sent, 300u);
  EXPECT_TRUE(h.connected);
}

TEST_P(EveryFraming, CorruptedAndDroppedStatesAreCountedNotUsed) {
  Rig rig(GetParam(), "faults");
  device::DeviceState state;
  int updates = 0;
  for (int tick = 0; tick < 100; ++tick) {
    rig.arm->send(device::DeviceCommand{});
    // every 10th state corrupted, every 10th (offset 5) dropped
    rig.device_tick(tick % 10 != 5, tick % 10 == 0);
    updates += rig.arm->poll(state) ? 1 : 0;
  }
  auto h = rig.arm->health();
  EXPECT_EQ(h.frames_bad, 10u);
  EXPECT_EQ(updates, 80);
  // a corrupted state and a dropped one both leave holes in the sequence; the first corrupt
  // state precedes the first valid one, so it is not a gap
  EXPECT_EQ(h.sequence_gaps, 19u);
  // every command was applied: an echo that moved on by two across a missing state is no loss
  EXPECT_EQ(h.commands_lost, 0u);
}

TEST_P(EveryFraming, TheWatchdogFaultReachesTheHost) {
  Rig rig(GetParam(), "watchdog");
  device::DeviceState state;
  device::DeviceCommand c;
  c.force_n[1] = 2.0;
  c.enable = true;
  for (int tick = 0; tick < 50; ++tick) {
    rig.arm->send(c);
    rig.device_tick();
    rig.arm->poll(state);
  }
  int ticks_until_seen = -1;
  for (int tick = 0; tick < 60 && ticks_until_seen < 0; ++tick) {  // host silent
    rig.device_tick();
    rig.arm->poll(state);
    if (state.fault & HF_FAULT_COMMAND_WATCHDOG) ticks_until_seen = tick;
  }
  // watchdog 20 ms: the last command arrived on the tick before silent tick 0, so silent tick 19
  // completes 20 ms; the firmware trips there and the host sees it in that very tick's state
  EXPECT_EQ(ticks_until_seen, 19);
  EXPECT_TRUE(state.status & HF_STATUS_WATCHDOG_TRIPPED);
  EXPECT_EQ(rig.firmware->record().applied_force_n[1], 0.0);
}

TEST_P(EveryFraming, AFrameFloodCannotHoldThePollingThread) {
  // Anyone on the bus (or a broken gateway) can send frames faster than the loop drains them. A
  // poll reads at most kDrainUnitBudget units and returns, so the 1 kHz tick keeps its budget; the
  // state behind the flood arrives a few polls later, each of which returned on its own.
  Rig rig(GetParam(), "flood");
  device::WireFrame junk;
  switch (GetParam()) {
    case Framing::can: junk.can_id = 0x054; junk.length = 8; break;  // STATE_POS of node 4, not ours
    case Framing::canfd: junk.can_id = 0x154; junk.fd = true; junk.length = 48; break;
    case Framing::hid: junk.data[0] = 1; junk.length = 64; break;  // protocol version 0: rejected
    case Framing::bulk: junk.length = 38; break;
  }
  int flooded = 0;
  for (int i = 0; i < 3 * device::kDrainUnitBudget; ++i)
    flooded += rig.device_link->transport().send(junk) == device::Io::ok ? 1 : 0;
  ASSERT_GT(flooded, device::kDrainUnitBudget) << "the bus took too few frames to flood a poll";
  rig.device_tick();  // one valid state, behind the flood
  device::DeviceState state;
  EXPECT_FALSE(rig.arm->poll(state)) << "one poll drained the whole flood";
  EXPECT_EQ(rig.arm->health().drains_cut_short, 1u);
  int polls = 1;
  while (!rig.arm->poll(state) && polls < 10) ++polls;
  EXPECT_LT(polls, 10) << "the state behind the flood never arrived";
}

TEST_P(EveryFraming, CommandsTheDeviceNeverAppliedAreCountedFromItsEcho) {
  // Every 4th command is lost on the way (discarded before the firmware sees it): the echo of the
  // next state skips it, and the driver counts it. 25 lost in 100 ticks; the last, on tick 99,
  // shows only when a later command is applied.
  Rig rig(GetParam(), "lostcmd");
  device::DeviceState state;
  for (int tick = 0; tick < 100; ++tick) {
    rig.arm->send(device::DeviceCommand{});
    if (tick % 4 == 3) {
      hf_message m;
      for (int budget = device::kDrainUnitBudget; rig.device_link->receive(m, budget) == device::Io::ok;) {
      }
    }
    rig.device_tick();
    rig.arm->poll(state);
  }
  EXPECT_EQ(rig.arm->health().commands_lost, 24u);
}

TEST_P(EveryFraming, TheEchoTimesEachCommandsRoundTripOnTheHostsClock) {
  // Each state whose echo moves on to one of our commands times that command: from its send to
  // the poll that received the state. A device that holds its states back shows as a long round
  // trip although they keep coming one per tick. Bounds from the host's own clock around the
  // calls, so the checks hold however slowly this machine runs.
  Rig rig(GetParam(), "round-trip");
  device::DeviceState state;
  for (int tick = 0; tick < 5; ++tick) {  // the echo moves on to ours
    rig.arm->send(device::DeviceCommand{});
    rig.device_tick();
    rig.arm->poll(state);
  }
  for (int tick = 0; tick < 20; ++tick) {
    const std::uint64_t before = rig.arm->health().echo_round_trips;
    const std::uint64_t t0 = device::monotonic_ns();
    rig.arm->send(device::DeviceCommand{});
    rig.device_tick();
    rig.arm->poll(state);
    const std::uint64_t t1 = device::monotonic_ns();
    ASSERT_EQ(rig.arm->health().echo_round_trips, before + 1) << "tick " << tick;
    EXPECT_LE(rig.arm->health().echo_round_trip_ns, t1 - t0) << "tick " << tick;
  }
  // The device takes the command at once but sends the state that echoes it 20 ms later.
  const std::uint64_t held_ns = 20'000'000;
  const std::uint64_t t0 = device::monotonic_ns();
  rig.arm->send(device::DeviceCommand{});
  rig.device_tick(/*send_state=*/false);
  while (device::monotonic_ns() < t0 + held_ns) rig.arm->poll(state);  // nothing echoes it meanwhile
  const std::uint64_t before = rig.arm->health().echo_round_trips;
  rig.device_tick();
  rig.arm->poll(state);
  const std::uint64_t t1 = device::monotonic_ns();
  ASSERT_EQ(rig.arm->health().echo_round_trips, before + 1);
  EXPECT_GE(rig.arm->health().echo_round_trip_ns, held_ns);
  EXPECT_LE(rig.arm->health().echo_round_trip_ns, t1 - t0);
}

TEST_P(EveryFraming, TheEchoSaysHowManyOfOurCommandsTheDeviceHasNotBeenSeenToTake) {
  // A device that takes every command echoes each in its next state: nothing outstanding beyond
  // the one in flight. One that stops reading (its commands discarded unread) keeps sending
  // states with the same echo: every command since counts as unheard, and hearing again clears it.
  Rig rig(GetParam(), "deaf");
  device::DeviceState state;
  auto unheard = [&] { return rig.arm->health().commands_sent - rig.arm->health().commands_sent_when_heard; };
  EXPECT_TRUE(rig.arm->health().echoes_commands);
  for (int tick = 0; tick < 50; ++tick) {
    rig.arm->send(device::DeviceCommand{});
    rig.device_tick();
    rig.arm->poll(state);
    if (tick > 2) {
      ASSERT_LE(unheard(), 1u) << "tick " << tick;
    }
  }
  for (int tick = 0; tick < 30; ++tick) {
    rig.arm->send(device::DeviceCommand{});
    hf_message m;
    for (int budget = device::kDrainUnitBudget; rig.device_link->receive(m, budget) == device::Io::ok;) {
    }
    rig.device_tick();
    rig.arm->poll(state);
  }
  EXPECT_GE(unheard(), 30u);
  for (int tick = 0; tick < 3; ++tick) {
    rig.arm->send(device::DeviceCommand{});
    rig.device_tick();
    rig.arm->poll(state);
  }
  EXPECT_LE(unheard(), 1u) << "the device hears again";
}

TEST_P(EveryFraming, AHostTakingOverFromAKilledOneCountsNoLostCommands) {
  // A host killed mid-run left the device echoing its last command (low byte 250). A new host
  // counts from 0, so the device takes its commands for late ones until its watchdog lets a new
  // host in; meanwhile the stale echo 250 looks like one of the new host's recent commands (0 is
  // 6 ahead of it, modulo 256). When the device then applies the new host's command ~20 ahead,
  // nothing was lost of the new host's stream that the device could have taken.
  Rig rig(GetParam(), "takeover");
  hf_message previous;
  std::memset(&previous, 0, sizeof previous);
  previous.type = HF_MSG_COMMAND;
  for (std::uint16_t seq = 0; seq <= 250; ++seq) {
    previous.seq = seq;
    rig.firmware->receive(previous, rig.t);
  }
  device::DeviceState state;
  for (int tick = 0; tick < 200; ++tick) {
    rig.arm->send(device::DeviceCommand{});
    rig.device_tick();
    rig.arm->poll(state);
  }
  EXPECT_EQ(state.command_echo, static_cast<std::uint8_t>(rig.arm->health().last_command_sequence))
      << "the device never took up the new host";
  EXPECT_EQ(rig.arm->health().commands_lost, 0u);
}

TEST_P(EveryFraming, AFaultedStatusHoldsAtOnceEvenWhenItsFaultMessageIsLost) {
  // Classic CAN carries the fault bits only in FAULT messages; the STATE's status bit 1 says
  // "faulted" in every frame set. When the FAULT message is lost (or still queued), the host
  // must not render force into a faulted device: the fault holds from that very state, as the
  // watchdog trip its status names.
  Rig rig(GetParam(), "faulted");
  device::DeviceState state;
  device::DeviceCommand c;
  c.force_n[1] = 2.0;
  c.enable = true;
  for (int tick = 0; tick < 50; ++tick) {
    rig.arm->send(c);
    rig.device_tick();
    rig.arm->poll(state);
  }
  for (int tick = 0; tick < 30 && !(state.status & HF_STATUS_FAULTED); ++tick) {  // host silent
    rig.device_tick(true, false, /*send_fault=*/false);
    rig.arm->poll(state);
  }
  ASSERT_TRUE(state.status & HF_STATUS_FAULTED) << "the firmware's watchdog did not trip";
  EXPECT_EQ(state.fault, std::uint32_t(HF_FAULT_COMMAND_WATCHDOG))
      << "a faulted state without its FAULT message must carry a fault";
}

TEST_P(EveryFraming, ADeviceThatRebootsMidRunIsTakenUpWithinAFewStates) {
  // A device that reboots starts its STATE counter again at 0. Far "behind" the last number seen,
  // its states would look old and be dropped until the counter caught up: up to 32 s of a live
  // device held at a link fault. Three states counting up one by one are a restart; the driver
  // takes the new counter and reports it, so the loop treats it as a link loss.
  Rig rig(GetParam(), "reboot");
  rig.state_seq = 30000;  // a device 30 s into its run (the low 8 bits on classic CAN)
  device::DeviceState state;
  for (int tick = 0; tick < 20; ++tick) {
    rig.arm->send(device::DeviceCommand{});
    rig.device_tick();
    rig.arm->poll(state);
  }
  ASSERT_EQ(state.sequence, std::uint16_t(rig.state_seq - 1) % rig.device_link->sequence_modulus());
  rig.firmware = std::make_unique<fake::FakeFirmware>(fake::DeviceModel{}, config::Pose{},
                                                      rig.device_link->sequence_modulus());
  rig.state_seq = 0;  // rebooted
  int states_until_taken = 0;
  bool taken = false;
  while (!taken && states_until_taken < 100) {
    rig.arm->send(device::DeviceCommand{});
    rig.device_tick();
    ++states_until_taken;
    taken = rig.arm->poll(state);
  }
  EXPECT_EQ(states_until_taken, 3) << "the restarted device's states were dropped as old";
  EXPECT_EQ(state.sequence, 2u);
  EXPECT_EQ(rig.arm->health().device_restarts, 1u);
  rig.device_tick();
  EXPECT_TRUE(rig.arm->poll(state)) << "and its stream goes on";
  EXPECT_EQ(rig.arm->health().device_restarts, 1u);
}

TEST_P(EveryFraming, ALateOrRepeatedStateIsDroppedNotTakenForARestart) {
  // One old state among new ones (a gateway's retransmission, a reordered frame) is dropped.
  Rig rig(GetParam(), "late");
  device::DeviceState state;
  for (int tick = 0; tick < 10; ++tick) {
    rig.device_tick();
    rig.arm->poll(state);
  }
  for (int repeat = 0; repeat < 5; ++repeat) {
    rig.state_seq = 3;  // the same old state again and again is no counter counting up
    rig.device_tick();
    EXPECT_FALSE(rig.arm->poll(state));
  }
  EXPECT_EQ(rig.arm->health().device_restarts, 0u);
}

TEST_P(EveryFraming, ABurstOfBadCommandFramesLatchesTheDevicesBadCommandsFault) {
  // Ten invalid command frames within 100 ms (a failing transceiver, a broken gateway) and the
  // device no longer trusts the stream: motors off, HF_FAULT_BAD_COMMANDS latched and reported,
  // as the host sees in the next state. A stray bad frame now and then is only counted.
  Rig rig(GetParam(), "badcmd");
  device::DeviceState state;
  device::DeviceCommand c;
  c.force_n[0] = 2.0;
  c.enable = true;
  for (int tick = 0; tick < 100; ++tick) {  // one bad command every 20 ms: 5 per 100 ms
    if (tick % 20 == 0) rig.arm->link().corrupt_next(1);
    rig.arm->send(c);
    rig.device_tick();
    rig.arm->poll(state);
  }
  ASSERT_EQ(rig.firmware->faults(), 0u) << "stray bad frames tripped the device";
  ASSERT_EQ(rig.firmware->record().applied_force_n[0], 2.0);
  for (int tick = 0; tick < 10; ++tick) {  // every command of 10 ms bad
    rig.arm->link().corrupt_next(1);
    rig.arm->send(c);
    rig.device_tick();
    rig.arm->poll(state);
  }
  EXPECT_TRUE(rig.firmware->faults() & HF_FAULT_BAD_COMMANDS);
  rig.arm->send(c);
  rig.device_tick();
  rig.arm->poll(state);
  EXPECT_EQ(rig.firmware->record().applied_force_n[0], 0.0) << "the motors stay off, good commands or not";
  EXPECT_TRUE(state.fault & HF_FAULT_BAD_COMMANDS) << "the host hears the cause";
}

INSTANTIATE_TEST_SUITE_P(Loopback, EveryFraming,
                         ::testing::Values(Framing::can, Framing::canfd, Framing::hid, Framing::bulk),
                         [](const auto& info) { return std::string(device::to_string(info.param)); });

TEST(LoopbackBus, RelaysHostFramesToAMonitorAndReportsBusOff) {
  const std::string path = socket_path("relay");
  device::LoopbackTransport bus(path, device::LoopbackRole::bus, device::LoopbackFormat::can);
  device::LoopbackTransport host(path, device::LoopbackRole::peer, device::LoopbackFormat::can);
  device::LoopbackTransport monitor(path, device::LoopbackRole::peer, device::LoopbackFormat::can);
  device::WireFrame f, got;
  while (bus.receive(got) == device::Io::ok) {}  // registrations
  EXPECT_EQ(bus.peer_count(), 2);
  f.can_id = 0x33;
  f.length = 8;
  f.data[0] = 0xAB;
  ASSERT_EQ(host.send(f), device::Io::ok);
  ASSERT_EQ(bus.receive(got), device::Io::ok);
  EXPECT_EQ(got.can_id, 0x33u);
  ASSERT_EQ(monitor.receive(got), device::Io::ok) << "the monitor sees host traffic";
  EXPECT_EQ(got.data[0], 0xAB);
  EXPECT_EQ(host.receive(got), device::Io::empty) << "nobody hears their own frames";

  device::WireFrame error;
  error.can_id = CAN_ERR_FLAG | CAN_ERR_BUSOFF;
  error.length = 8;
  bus.send(error);
  EXPECT_EQ(host.receive(got), device::Io::empty) << "error frames are not data";
  EXPECT_TRUE(host.error_flags() & device::kBusOff);
  error.can_id = CAN_ERR_FLAG | CAN_ERR_RESTARTED;
  bus.send(error);
  host.receive(got);
  EXPECT_FALSE(host.error_flags() & device::kBusOff) << "a restarted controller clears bus-off";
}

TEST(LoopbackBus, ACommandForOurDeviceThatWeDidNotSendIsCountedAsForeign) {
  // Any local user can open a raw CAN socket and command our node, bypassing the host's safety
  // layer. The host hears every frame for its node but never its own: a command it hears is
  // someone else's, which the driver reports (the loop latches zero force on it).
  for (Framing framing : {Framing::can, Framing::canfd}) {
    SCOPED_TRACE(device::to_string(framing));
    Rig rig(framing, "foreign");
    device::DeviceState state;
    for (int tick = 0; tick < 20; ++tick) {
      rig.arm->send(device::DeviceCommand{});
      rig.device_tick();
      rig.arm->poll(state);
    }
    EXPECT_EQ(rig.arm->health().foreign_commands, 0u) << "our own commands are not foreign";
    device::MessageLink intruder(
        std::make_unique<device::LoopbackTransport>(rig.path, device::LoopbackRole::peer, device::LoopbackFormat::can),
        framing, 3, device::Side::host);
    hf_message m;
    std::memset(&m, 0, sizeof m);
    m.type = HF_MSG_COMMAND;
    m.seq = 21;  // just ahead of ours: the device would take it
    m.body.command.force_n[0] = 20.0;
    m.body.command.flags = HF_CMD_ENABLE;
    ASSERT_TRUE(intruder.send(m));
    rig.device_tick();
    rig.arm->poll(state);
    EXPECT_EQ(rig.arm->health().foreign_commands, 1u);
  }
}

TEST(LoopbackBus, APeerStartedBeforeItsBusIsDisconnectedUntilTheBusAppears) {
  // The host may come up first (a device powered on later, a fake device restarted last): its
  // link reports kDisconnected, without blocking, and connects by itself once the bus is there.
  const std::string path = socket_path("later");
  ::unlink(path.c_str());
  device::LoopbackTransport host(path, device::LoopbackRole::peer, device::LoopbackFormat::bulk);
  EXPECT_TRUE(host.error_flags() & device::kDisconnected);
  device::WireFrame f;
  f.length = 6;
  EXPECT_EQ(host.send(f), device::Io::error);
  device::LoopbackTransport bus(path, device::LoopbackRole::bus, device::LoopbackFormat::bulk);
  ::usleep(110'000);  // reconnection attempts are at most every 100 ms
  EXPECT_EQ(host.send(f), device::Io::ok);
  EXPECT_FALSE(host.error_flags() & device::kDisconnected);
  EXPECT_EQ(host.reconnects(), 1u) << "the driver restarts its sequence tracking on it";
  device::WireFrame got;
  for (int i = 0; i < 100 && bus.receive(got) != device::Io::ok; ++i) ::usleep(1000);
  EXPECT_EQ(got.length, 6u) << "the frame reached the bus";
}

TEST(LoopbackBus, APeerWhoseBusPathIsUnusableFailsNamingIt) {
  try {
    device::LoopbackTransport peer("/dev/null/bus.sock", device::LoopbackRole::peer,
                                   device::LoopbackFormat::can);
    FAIL() << "opened a peer on an impossible path";
  } catch (const device::TransportError& e) {
    EXPECT_NE(std::string(e.what()).find("/dev/null/bus.sock"), std::string::npos) << e.what();
  }
}

// A device that restarts (or is replugged) while the host keeps running starts its STATE counter
// anew. Judged against the old counter, its states would look "older" for up to half the
// modulus (32 s at 1 kHz) and be dropped: the host would feel nothing and, worse, see no fresh
// state while the link is fine. The driver restarts its sequence tracking when the transport
// reports a reconnection (the same rule serves libusb's replug recovery).
TEST(LoopbackBus, ADriverFollowsADeviceWhoseCountersRestartedAfterAReconnection) {
  Rig rig(Framing::bulk, "restart");
  device::DeviceState state;
  rig.state_seq = 10000;
  for (int tick = 0; tick < 20; ++tick) {
    rig.device_tick();
    rig.arm->poll(state);
  }
  ASSERT_EQ(state.sequence, 10019);
  // The device process restarts: its bus goes away and comes back with fresh counters.
  rig.device_link.reset();
  EXPECT_FALSE(rig.arm->poll(state));
  EXPECT_FALSE(rig.arm->health().connected);
  rig.device_link = std::make_unique<device::MessageLink>(
      std::make_unique<device::LoopbackTransport>(rig.path, device::LoopbackRole::bus, device::LoopbackFormat::bulk),
      Framing::bulk, 3, device::Side::device);
  rig.state_seq = 0;  // 0 - 10019 mod 65536 = 55517: "older" than 10019 to a tracker that was not reset
  // The peer reconnects by itself, at most every 100 ms: poll like the loop until it has (2 s bound).
  bool fresh = false;
  for (int tick = 0; tick < 2000 && !fresh; ++tick) {
    rig.device_tick();
    fresh = rig.arm->poll(state) && state.sequence < 10000;
    usleep(1000);
  }
  ASSERT_TRUE(fresh) << "no state of the restarted device was accepted";
  EXPECT_TRUE(rig.arm->health().connected);
  EXPECT_EQ(rig.arm->link().transport().reconnects(), 1u);
}

TEST(LoopbackBus, AHostLosesItsBusAndNoticesWithoutBlocking) {
  const std::string path = socket_path("lost");
  auto bus = std::make_unique<device::LoopbackTransport>(path, device::LoopbackRole::bus, device::LoopbackFormat::bulk);
  device::LoopbackTransport host(path, device::LoopbackRole::peer, device::LoopbackFormat::bulk);
  bus.reset();  // the device process died
  device::WireFrame f;
  f.length = 6;
  EXPECT_EQ(host.send(f), device::Io::error);
  EXPECT_TRUE(host.error_flags() & device::kDisconnected);
}

}  // namespace
