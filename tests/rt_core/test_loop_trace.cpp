// What each trace record names, so a tick can be tied to the device and the sim on one clock
// (hapfluid.motion_to_force_latency): the STATE frame whose pose the tick used, the COMMAND it
// sent (wire sequence numbers, protocol.md §3) and the device_states tick the rendered sim sample
// was computed from.
#include <gtest/gtest.h>

#include "hapfluid/config/rig.hpp"
#include "hapfluid/rt/loop.hpp"
#include "loop_test_rig.hpp"

using namespace hapfluid;

namespace {

// A fresh frame on every other poll, numbered like a classic-CAN link (8 bits, wraps); commands
// numbered as the arm driver numbers them (the first one goes out as 0).
class NumberedDevice final : public device::Device {
 public:
  std::uint16_t next_state = 250;  // wraps within the test
  std::uint16_t next_command = 0;
  std::uint64_t polls = 0;
  NumberedDevice() { health_.connected = true; }
  bool poll(device::DeviceState& out) override {
    if (++polls % 2 == 0) return false;
    out = {};
    out.host_receive_ns = shm::monotonic_ns();
    out.sequence = next_state;
    next_state = static_cast<std::uint16_t>((next_state + 1) % 256);
    return true;
  }
  bool send(const device::DeviceCommand&) override {
    health_.last_command_sequence = next_command++;
    ++health_.commands_sent;
    return true;
  }
  device::DeviceHealth health() const override { return health_; }
  const char* name() const override { return "numbered"; }

 private:
  device::DeviceHealth health_;
};

}  // namespace

TEST(LoopTrace, EveryRecordNamesTheStateFrameUsedTheCommandSentAndTheSimSamplesDeviceTick) {
  config::Rig rig = rt_test::one_device_rig("arm", "trace-test", 64);
  auto owned = std::make_unique<NumberedDevice>();
  NumberedDevice* device = owned.get();
  auto owned_loop = rt_test::one_device_loop(rig, std::move(owned));
  rt::RtLoop& loop = *owned_loop;
  auto test_sim = rt_test::test_sim(rig);
  shm::LatestWriter& sim = test_sim->writer;

  std::uint64_t now = shm::monotonic_ns();
  auto tick = [&] {
    loop.tick(now, now);
    now += 1'000'000;
  };
  for (int i = 0; i < 3; ++i) tick();
  EXPECT_EQ(loop.last_trace().sim_device_tick, 0u) << "no sim sample yet";

  loop.offer_sim(&test_sim->attachment);
  shm::SimSample sample{};
  sample.device_tick = 2;  // computed from the pose the loop published at tick 2
  sample.publish_ns = shm::monotonic_ns();
  sim.publish(sample);
  tick();
  EXPECT_EQ(loop.last_trace().sim_device_tick, 2u);
  EXPECT_EQ(loop.last_trace().sim_publish_ns, sample.publish_ns);
  // The commands leave after the sample was read: a sample published before the tick's send.
  EXPECT_GE(loop.last_trace().send_ns, sample.publish_ns);
  tick();
  EXPECT_EQ(loop.last_trace().sim_device_tick, 2u) << "the sample stays in use until a newer one";

  // Ticks 1..5 polled frames 250 (fresh), -, 251, -, 252: a tick without a fresh frame still uses
  // the newest one it has. Commands 0..4, one per tick.
  shm::RingReader reader(loop.trace_ring().segment(), 0);
  shm::TraceRecord r{};
  std::uint64_t previous_receive_ns = 0;
  const std::uint16_t expected_state[] = {250, 250, 251, 251, 252};
  for (int i = 0; i < 5; ++i) {
    ASSERT_TRUE(reader.next(r));
    EXPECT_EQ(r.tick, std::uint64_t(i + 1));
    EXPECT_EQ(r.devices[0].fresh, i % 2 == 0 ? 1u : 0u);
    EXPECT_EQ(r.devices[0].state_sequence, expected_state[i]) << "tick " << r.tick;
    EXPECT_EQ(r.devices[0].command_sequence, i) << "tick " << r.tick;
    EXPECT_GT(r.devices[0].state_receive_ns, 0u);
    EXPECT_LE(r.devices[0].state_receive_ns, r.send_ns) << "the frame arrived before the tick sent";
    if (i % 2 == 1) {
      EXPECT_EQ(r.devices[0].state_receive_ns, previous_receive_ns) << "no fresh frame: the old one's arrival";
    }
    previous_receive_ns = r.devices[0].state_receive_ns;
  }
  for (int i = 0; i < 10; ++i) tick();
  EXPECT_EQ(loop.last_trace().devices[0].state_sequence, (250 + 7) % 256) << "8-bit numbers wrap as on the wire";
  EXPECT_EQ(loop.last_trace().devices[0].command_sequence, 14);
  EXPECT_EQ(device->next_command, 15);
  sim.close();
}
