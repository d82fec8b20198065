// The 1 kHz loop allocates nothing and takes no lock after start-up (issue 5; style: "real-time
// code reads like real-time code"). This binary replaces operator new/delete, malloc & co. and
// pthread_mutex_lock with counting versions that count only on the loop's thread, runs the real
// RtLoop::run() for 1.5 s at 1 kHz through every path (sim samples in both wrench modes, NaN
// samples, a silenced device = link fault and recovery, e-stop and reset, sim restart with a
// re-attach), and requires zero of both.
#include <dlfcn.h>
#include <gtest/gtest.h>
#include <pthread.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <new>
#include <thread>

#include "hapfluid/config/rig.hpp"
#include "hapfluid/rt/loop.hpp"
#include "hapfluid/rt/simulated_device.hpp"

extern "C" void* __libc_malloc(size_t);
extern "C" void* __libc_calloc(size_t, size_t);
extern "C" void* __libc_realloc(void*, size_t);
extern "C" void __libc_free(void*);

namespace {
thread_local bool t_counting = false;
std::atomic<long> g_allocations{0};
std::atomic<long> g_locks{0};
void count_allocation() {
  if (t_counting) g_allocations.fetch_add(1, std::memory_order_relaxed);
}
}  // namespace

extern "C" {
void* malloc(size_t n) {
  count_allocation();
  return __libc_malloc(n);
}
void* calloc(size_t a, size_t b) {
  count_allocation();
  return __libc_calloc(a, b);
}
void* realloc(void* p, size_t n) {
  count_allocation();
  return __libc_realloc(p, n);
}
void free(void* p) { __libc_free(p); }
int pthread_mutex_lock(pthread_mutex_t* m) {
  using Fn = int (*)(pthread_mutex_t*);
  static Fn real = reinterpret_cast<Fn>(dlsym(RTLD_NEXT, "pthread_mutex_lock"));
  if (t_counting) g_locks.fetch_add(1, std::memory_order_relaxed);
  return real(m);
}
}

void* operator new(std::size_t n) {
  count_allocation();
  if (void* p = __libc_malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t n) { return operator new(n); }
void operator delete(void* p) noexcept { __libc_free(p); }
void operator delete[](void* p) noexcept { __libc_free(p); }
void operator delete(void* p, std::size_t) noexcept { __libc_free(p); }
void operator delete[](void* p, std::size_t) noexcept { __libc_free(p); }

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

TEST(LoopAllocations, CountersSeeAllocationsAndLocksOnTheCountingThread) {
  // Control: the hooks are really in place (otherwise the zero below would prove nothing).
  t_counting = true;
  delete new int(1);
  free(malloc(16));
  pthread_mutex_t mutex = PTHREAD_MUTEX_INITIALIZER;
  pthread_mutex_lock(&mutex);
  pthread_mutex_unlock(&mutex);
  t_counting = false;
  EXPECT_EQ(g_allocations.exchange(0), 2);
  EXPECT_EQ(g_locks.exchange(0), 1);
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
      }
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

  loop.run(200'000'000);  // start-up: first faults, first samples, every branch warmed once
  std::uint64_t warm_ticks = loop.ticks();
  t_counting = true;
  loop.run(1'500'000'000);
  t_counting = false;
  stop.store(true);
  sim_thread.join();

  std::uint64_t counted_ticks = loop.ticks() - warm_ticks;
  // ~1500 on an idle machine; the floor only proves the loop ran through every phase below.
  EXPECT_GT(counted_ticks, 500u);
  EXPECT_EQ(g_allocations.load(), 0) << "allocations inside the loop";
  EXPECT_EQ(g_locks.load(), 0) << "mutex locks inside the loop";
  EXPECT_EQ(loop.sim_epoch_in_use(), 2u) << "the loop moved to the restarted sim's segment";
  EXPECT_GT(loop.link_quality(0).longest_miss_run, 5u) << "the link-fault path was exercised";
  sim.close();
}
