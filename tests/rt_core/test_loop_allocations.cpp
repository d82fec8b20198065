// The 1 kHz loop allocates nothing, takes no lock and makes no system call but its own sleep
// after start-up (style: "real-time code reads like real-time code"). The counters
// (thread_counters.hpp: replaced malloc & co. and pthread lock calls, a seccomp watch for system
// calls) count only on the loop's thread, which runs the real RtLoop::run() for 1.5 s at 1 kHz
// through every path (sim samples in both wrench modes, NaN samples, a silenced device = link
// fault and recovery, e-stop and reset, sim restart with a re-attach) and requires zero of each.
// The devices here are simulated; hil-loop-io-check (tests/hil-kernel/harness) holds the real
// transports to the same counters on a real kernel.
#include <gtest/gtest.h>
#include <pthread.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <thread>

#include "hapfluid/config/rig.hpp"
#include "hapfluid/rt/loop.hpp"
#include "hapfluid/rt/simulated_device.hpp"
#include "thread_counters.hpp"

using namespace hapfluid;

namespace {

const char* kRig = R"(
name = "alloc-test"
[rt]
trace_ring_records = 4096
flight_recorder_ticks = 200
[[devices]]
name = "left"
wrench_mode = "interpolate"
sim_stale_ms = 30.0
[devices.transport]
kind = "loopback"
address = "/tmp/unused-left"
[[devices]]
name = "right"
wrench_mode = "coupling"
[devices.transport]
kind = "loopback"
address = "/tmp/unused-right"
)";

}  // namespace

TEST(LoopAllocations, CountersSeeAllocationsLocksAndSystemCallsOnTheCountingThread) {
  // Control: the hooks are really in place (otherwise the zeros below would prove nothing).
  counters::SyscallWatch watch;
  std::string why;
  std::thread watched([&] {
    ASSERT_TRUE(watch.watch_this_thread(why)) << why;
    counters::count_on_this_thread(true);
    int* volatile object = new int(1);  // volatile: the compiler may not elide the pair
    delete object;
    void* volatile block = malloc(16);
    free(block);
    pthread_mutex_t mutex = PTHREAD_MUTEX_INITIALIZER;
    pthread_mutex_lock(&mutex);
    pthread_mutex_unlock(&mutex);
    watch.start();  // after this thread's first allocation, which maps its malloc arena
    (void)!::write(-1, "", 0);
    (void)::getppid();
    timespec nap{0, 1000};
    clock_nanosleep(CLOCK_MONOTONIC, 0, &nap, nullptr);  // the loop's own sleep: not counted
    watch.stop();
    counters::count_on_this_thread(false);
  });
  watched.join();
  EXPECT_EQ(counters::allocations(), 2);
  EXPECT_EQ(counters::locks(), 1);
  EXPECT_EQ(watch.total(), 2) << watch.summary();
  counters::reset_counts();
}

TEST(LoopAllocations, LoopAllocatesNothingAndTakesNoLockAfterStartUp) {
  config::Rig rig = config::parse_rig(kRig, "alloc-test.toml");
  rig.rt.shm.prefix = "hapfluid-alloc-" + std::to_string(::getpid());
  std::vector<std::unique_ptr<device::Device>> devices;
  devices.push_back(std::make_unique<rt::SimulatedDevice>("left"));
  devices.push_back(std::make_unique<rt::SimulatedDevice>("right"));
  auto* left = static_cast<rt::SimulatedDevice*>(devices[0].get());
  rt::RtLoop loop(rig, std::move(devices));

  const std::string sim_name = shm::segment_name(rig.rt.shm.prefix, shm::ChannelKind::sim_samples);
  auto sim = shm::LatestWriter::create(sim_name, shm::ChannelKind::sim_samples, sizeof(shm::SimSample));
  rt::SimAttachment first{shm::LatestReader::attach(sim_name, shm::ChannelKind::sim_samples, sizeof(shm::SimSample)), 1};
  loop.offer_sim(&first);
  rt::SimAttachment second;  // filled when the sim "restarts"

  // The sim side, on its own thread, does everything that is allowed to be slow.
  std::atomic<bool> stop{false};
  std::thread sim_thread([&] {
    shm::SimSample sample{};
    sample.device_count = 2;
    for (int step = 0; !stop.load(); ++step) {
      for (int d = 0; d < 2; ++d) {
        auto& m = sample.couplings[d];
        m.valid = 1;
        m.force_n[2] = 0.5 * std::sin(step * 0.05);
        m.q0[0] = 1;
        m.stiffness_n_per_m = 300;
        m.damping_n_s_per_m = 2;
        m.angular_stiffness_nm_per_rad = 0.5;
        m.vref_m_s[0] = 0.1;  // the anchor moving on: the ring of poll times is read every tick
        m.wref_rad_s[2] = 2.0;
      }
      sample.device_tick = static_cast<std::uint64_t>(step) + 1;
      if (step % 50 == 7) sample.couplings[0].force_n[0] = NAN;  // hostile sample
      sample.sequence = step;
      sample.publish_ns = shm::monotonic_ns();
      sim.publish(sample);
      sample.couplings[0].force_n[0] = 0;
      if (step == 40) left->set_silent(true);   // link fault on "left"
      if (step == 55) left->set_silent(false);  // ... and recovery
      if (step == 70) loop.request_estop();
      if (step == 90) loop.request_estop_reset();
      if (step == 110) {  // sim restart: new segment, re-attached as the supervisor would
        sim.close();
        sim = shm::LatestWriter::create(sim_name, shm::ChannelKind::sim_samples, sizeof(shm::SimSample));
        second.reader = shm::LatestReader::attach(sim_name, shm::ChannelKind::sim_samples, sizeof(shm::SimSample));
        second.epoch = 2;
        loop.offer_sim(&second);
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(10));  // 100 Hz sim
    }
  });

  counters::SyscallWatch watch;
  std::string refused;
  std::uint64_t warm_ticks = 0;
  std::thread loop_thread([&] {  // the filter stays with this thread, which ends here
    if (!watch.watch_this_thread(refused)) return;
    loop.run(200'000'000);  // start-up: first faults, first samples, every branch warmed once
    warm_ticks = loop.ticks();
    counters::count_on_this_thread(true);
    watch.start();
    loop.run(1'500'000'000);
    watch.stop();
    counters::count_on_this_thread(false);
  });
  loop_thread.join();
  stop.store(true);
  sim_thread.join();
  ASSERT_TRUE(refused.empty()) << refused;

  std::uint64_t counted_ticks = loop.ticks() - warm_ticks;
  // ~1500 on an idle machine; the floor only proves the loop ran through every phase below.
  EXPECT_GT(counted_ticks, 500u);
  EXPECT_EQ(counters::allocations(), 0) << "allocations inside the loop";
  EXPECT_EQ(counters::locks(), 0) << "mutex locks inside the loop";
  EXPECT_EQ(watch.total(), 0) << "system calls inside the loop besides its sleep: " << watch.summary();
  EXPECT_EQ(loop.sim_epoch_in_use(), 2u) << "the loop moved to the restarted sim's segment";
  EXPECT_GT(loop.link_quality(0).longest_miss_run, 5u) << "the link-fault path was exercised";
  sim.close();
}
