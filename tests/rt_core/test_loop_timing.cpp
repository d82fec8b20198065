// The loop's pacing: absolute-time wake-ups on the period grid, and re-phasing after an overrun
// (missed slots are skipped and counted, never run back to back). A slow device at the device
// boundary makes every 50th tick take 2.5 ms.
#include <gtest/gtest.h>
#include <pthread.h>
#include <sched.h>
#include <unistd.h>

#include <atomic>
#include <thread>

#include "hapfluid/config/rig.hpp"
#include "hapfluid/rt/loop.hpp"
#include "hapfluid/rt/rt_setup.hpp"
#include "hapfluid/rt/simulated_device.hpp"
#include "loop_test_rig.hpp"

using namespace hapfluid;

namespace {

class SlowDevice final : public device::Device {
 public:
  bool poll(device::DeviceState& out) override {
    if (++polls_ % 50 == 0) {  // a 2.5 ms stall: the next two 1 ms slots are already gone
      std::uint64_t until = shm::monotonic_ns() + 2'500'000;
      while (shm::monotonic_ns() < until) {
      }
    }
    return inner_.poll(out);
  }
  bool send(const device::DeviceCommand& c) override { return inner_.send(c); }
  device::DeviceHealth health() const override { return inner_.health(); }
  const char* name() const override { return "slow"; }

 private:
  rt::SimulatedDevice inner_{"slow"};
  std::uint64_t polls_ = 0;
};

}  // namespace

TEST(LoopTiming, OverrunsAreCountedAndTheLoopRephasesInsteadOfBursting) {
  config::Rig rig = rt_test::one_device_rig("slow", "timing-test");
  std::vector<std::unique_ptr<device::Device>> devices;
  devices.push_back(std::make_unique<SlowDevice>());
  rt::RtLoop loop(rig, std::move(devices));
  loop.run(400'000'000);

  shm::RingReader reader(loop.trace_ring().segment(), 0);
  shm::TraceRecord r{}, previous{};
  int records = 0, rephased = 0;
  while (reader.next(r)) {
    EXPECT_EQ(r.scheduled_ns % 1'000'000, 250'000u) << "wake-ups stay on the absolute 1 ms grid, a quarter period off the kernel tick";
    EXPECT_GE(r.wake_ns, r.scheduled_ns) << "never woken early";
    if (records > 0) {
      std::uint64_t step = r.scheduled_ns - previous.scheduled_ns;
      EXPECT_GE(step, 1'000'000u) << "no burst: two ticks never share a slot";
      if (step > 1'000'000) {
        // Every skipped slot is counted once (a busy CI machine adds its own late wake-ups).
        EXPECT_EQ(step, (r.overruns - previous.overruns + 1) * 1'000'000u);
        EXPECT_TRUE(r.loop_flags & rt::loop_overrun);
        if (step == 3'000'000) ++rephased;  // a 2.5 ms tick skips the two slots it overran
      }
    }
    previous = r;
    ++records;
  }
  EXPECT_GT(records, 150) << "the loop ran (about 380 ticks on an idle machine)";
  EXPECT_GE(rephased, 4) << "every 50th tick stalls for 2.5 ms";
  // The trace's running count matches the loop's: only the final, untraced wake-up may add its
  // own overruns (a few slots, or more when a loaded test machine wakes the thread late).
  EXPECT_GE(loop.overruns(), previous.overruns);
  EXPECT_LE(loop.overruns(), previous.overruns + 100);
}

TEST(LoopTiming, TheWakePhaseDefaultsToAQuarterPeriodAndMustLieInsideThePeriod) {
  // Off the kernel's scheduler tick by default (whole multiples of the period coincide with it).
  const std::string device = "[[devices]]\nname = \"a\"\n[devices.transport]\nkind = \"loopback\"\naddress = \"/tmp/unused\"\n";
  config::Rig rig = config::parse_rig("[rt]\nperiod_ns = 2000000\n" + device, "phase-default.toml");
  EXPECT_EQ(rig.rt.wake_phase_ns, 500'000);
  EXPECT_EQ(config::parse_rig("[rt]\nwake_phase_ns = 0\n" + device, "phase-zero.toml").rt.wake_phase_ns, 0);
  try {
    config::parse_rig("[rt]\nwake_phase_ns = 1000000\n" + device, "phase-bad.toml");
    ADD_FAILURE() << "accepted a phase of a whole period";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("wake_phase_ns"), std::string::npos) << e.what();
  }
}

TEST(RtSetup, HelperThreadsAreMovedOffTheLoopsCpu) {
  // A device reopen worker (created before the RT set-up, so allowed on every CPU) must not run
  // its open() syscalls on the loop's CPU: a non-PREEMPT_RT kernel would not preempt them.
  cpu_set_t allowed;
  sched_getaffinity(0, sizeof allowed, &allowed);
  if (sysconf(_SC_NPROCESSORS_ONLN) < 2 || !CPU_ISSET(0, &allowed) || !CPU_ISSET(1, &allowed))
    GTEST_SKIP() << "needs CPUs 0 and 1";
  std::atomic<bool> stop{false};
  std::thread helper([&] {
    while (!stop.load()) usleep(1000);
  });
  EXPECT_GE(hapfluid::rt::keep_other_threads_off_cpu(0), 1);
  cpu_set_t set;
  ASSERT_EQ(pthread_getaffinity_np(helper.native_handle(), sizeof set, &set), 0);
  EXPECT_FALSE(CPU_ISSET(0, &set));
  EXPECT_TRUE(CPU_ISSET(1, &set));
  stop = true;
  helper.join();
}
