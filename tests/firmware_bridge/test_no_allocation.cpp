// The 1 kHz loop's rule: after open, Device::poll and Device::send neither allocate nor free.
// Global operator new/delete are replaced in this test binary to count calls on the test's own
// thread (the loop's, here; a transport's reopen worker may allocate on its own) while a driver
// exchanges 1000 ticks with the emulated firmware over the loopback bus, and while a driver
// whose device is absent at start waits for it.
#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <cstdlib>
#include <cstring>
#include <new>

#include "fake_firmware.hpp"
#include "hapfluid/device/haptic_arm.hpp"
#include "hapfluid/device/loopback.hpp"
#include "hapfluid/device/open_device.hpp"

namespace {
std::atomic<long> g_allocations{0};
thread_local bool t_counting = false;
void count() {
  if (t_counting) g_allocations.fetch_add(1, std::memory_order_relaxed);
}
// Counts on the constructing thread while it lives.
struct CountingHere {
  CountingHere() { t_counting = true; }
  ~CountingHere() { t_counting = false; }
};
}  // namespace

void* operator new(std::size_t n) {
  count();
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept {
  if (p) count();
  std::free(p);
}
void operator delete(void* p, std::size_t) noexcept {
  if (p) count();
  std::free(p);
}

namespace {

using namespace hapfluid;

TEST(RealTimeRules, PollAndSendNeitherAllocateNorFree) {
  const std::string path = "/tmp/hapfluid-test-alloc-" + std::to_string(::getpid()) + ".sock";
  device::MessageLink device_link(
      std::make_unique<device::LoopbackTransport>(path, device::LoopbackRole::bus, device::LoopbackFormat::can),
      device::Framing::can, 1, device::Side::device);
  device::HapticArm arm("alloc", std::make_unique<device::MessageLink>(
                                     std::make_unique<device::LoopbackTransport>(path, device::LoopbackRole::peer,
                                                                                 device::LoopbackFormat::can),
                                     device::Framing::can, 1, device::Side::host),
                        0);
  fake::FakeFirmware firmware(fake::DeviceModel{}, config::Pose{}, 256);
  device::DeviceState state;
  device::DeviceCommand command;
  command.force_n[2] = 1.0;
  command.enable = true;
  long device_side = 0;
  CountingHere counting;
  const long before = g_allocations.load();
  for (int tick = 0; tick < 1000; ++tick) {
    arm.send(command);
    const long mark = g_allocations.load();
    hf_message m;
    for (int budget = device::kDrainUnitBudget; device_link.receive(m, budget) == device::Io::ok;)
      firmware.receive(m, tick * 1e-3);
    firmware.step(tick * 1e-3, 1e-3, config::PoseTwist{});
    std::memset(&m, 0, sizeof m);
    m.type = HF_MSG_STATE;
    m.seq = static_cast<std::uint16_t>(tick);
    m.body.state = firmware.state(0);
    device_link.send(m);
    device_side += g_allocations.load() - mark;
    arm.poll(state);
    (void)arm.health();
  }
  EXPECT_EQ(g_allocations.load() - before - device_side, 0) << "host driver allocated in the loop";
  EXPECT_GT(state.position_m[2], 0.0) << "the exchange really happened";
}

TEST(RealTimeRules, ADriverWaitingForAnAbsentDeviceNeitherAllocatesNorFrees) {
  // The arm is not plugged in (none is on a CI machine): the loop keeps calling poll and send
  // every tick while the transport's worker looks for the device on its own thread.
  config::RigDevice d;
  d.name = "absent";
  d.transport.kind = config::TransportKind::hid;
  d.transport.address = "1209:4846";
  std::unique_ptr<device::Device> arm;
  try {
    arm = device::open_device(d);
  } catch (const device::TransportError& e) {
    GTEST_SKIP() << "no HID device can appear on this machine: " << e.what();
  }
  ASSERT_TRUE(arm->health().transport_errors & device::kDisconnected) << "a hapfluid arm is attached";
  device::DeviceState state;
  device::DeviceCommand command;
  command.enable = true;
  CountingHere counting;
  const long before = g_allocations.load();
  for (int tick = 0; tick < 500; ++tick) {  // 0.5 s: the worker searches twice or more meanwhile
    arm->poll(state);
    arm->send(command);
    (void)arm->health();
    ::usleep(1000);
  }
  EXPECT_EQ(g_allocations.load() - before, 0) << "the loop's calls allocated while the device was absent";
}

}  // namespace
