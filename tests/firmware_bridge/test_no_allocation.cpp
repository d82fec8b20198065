// The 1 kHz loop's rule: after open, Device::poll and Device::send neither allocate nor free.
// Global operator new/delete are replaced in this test binary to count calls while a driver
// exchanges 1000 ticks with the emulated firmware over the loopback bus.
#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <cstdlib>
#include <cstring>
#include <new>

#include "fake_firmware.hpp"
#include "hapfluid/device/haptic_arm.hpp"
#include "hapfluid/device/loopback.hpp"

namespace {
std::atomic<long> g_allocations{0};
}

void* operator new(std::size_t n) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept {
  if (p) g_allocations.fetch_add(1, std::memory_order_relaxed);
  std::free(p);
}
void operator delete(void* p, std::size_t) noexcept {
  if (p) g_allocations.fetch_add(1, std::memory_order_relaxed);
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
  const long before = g_allocations.load();
  for (int tick = 0; tick < 1000; ++tick) {
    arm.send(command);
    const long mark = g_allocations.load();
    hf_message m;
    while (device_link.receive(m) == device::Io::ok) firmware.receive(m, tick * 1e-3);
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

}  // namespace
