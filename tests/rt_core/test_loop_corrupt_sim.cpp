// A sim_samples segment spoiled after haptic-rt attached (header rewritten, object shrunk) is a
// dead sim to the loop: no sample from it is ever rendered, and the wrench ramps down on the
// staleness rule exactly as when the sim process dies, while the loop keeps running.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/mman.h>
#include <unistd.h>

#include <chrono>
#include <functional>
#include <thread>

#include "hapfluid/config/rig.hpp"
#include "hapfluid/rt/loop.hpp"
#include "hapfluid/rt/rt_setup.hpp"
#include "hapfluid/rt/simulated_device.hpp"
#include "hapfluid/safety/flags.hpp"
#include "loop_test_rig.hpp"

using namespace hapfluid;

namespace {

// Runs the loop on a healthy sim for 20 ticks, spoils the segment, then ticks on while the sim
// keeps publishing (a broken sim need not stop) until the staleness fault appears. The loop ages
// samples on CLOCK_MONOTONIC, so ticks are paced at its 1 ms period.
void expect_spoiled_sim_faults_like_a_dead_one(const char* tag, const std::function<void(shm::LatestWriter&)>& spoil) {
  config::Rig rig = rt_test::one_device_rig("arm", tag);
  std::vector<std::unique_ptr<device::Device>> devices;
  devices.push_back(std::make_unique<rt::SimulatedDevice>("arm"));
  rt::RtLoop loop(rig, std::move(devices));
  const std::string sim_name = shm::segment_name(rig.rt.shm.prefix, shm::ChannelKind::sim_samples);
  auto sim = shm::LatestWriter::create(sim_name, shm::ChannelKind::sim_samples, sizeof(shm::SimSample));
  rt::SimAttachment attachment{shm::LatestReader::attach(sim_name, shm::ChannelKind::sim_samples, sizeof(shm::SimSample)), 1};
  loop.offer_sim(&attachment);

  shm::SimSample sample{};
  sample.device_count = 1;
  std::uint64_t tick_ns = 0;
  auto step = [&] {
    ++sample.sequence;
    sample.publish_ns = shm::monotonic_ns();
    sim.publish(sample);
    tick_ns = shm::monotonic_ns();
    loop.tick(tick_ns, tick_ns);
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  };
  for (int i = 0; i < 20; ++i) step();
  ASSERT_NE(loop.last_trace().loop_flags & rt::loop_new_sim_sample, 0u) << "the healthy sim is read";
  ASSERT_EQ(loop.last_trace().devices[0].faults & safety::fault_sim_stale, 0u);

  const std::uint64_t last_healthy_tick_ns = tick_ns;  // the newest usable sample arrived then
  spoil(sim);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  while ((loop.last_trace().devices[0].faults & safety::fault_sim_stale) == 0 &&
         std::chrono::steady_clock::now() < deadline) {
    step();
    const shm::TraceRecord& t = loop.last_trace();
    ASSERT_EQ(t.loop_flags & rt::loop_new_sim_sample, 0u) << "tick " << t.tick << " rendered a spoiled sample";
    ASSERT_NE(t.loop_flags & rt::loop_sim_not_attached, 0u) << "tick " << t.tick;
  }
  ASSERT_NE(loop.last_trace().devices[0].faults & safety::fault_sim_stale, 0u) << "no staleness fault within 5 s";
  // The dead-sim rule and not another one: the fault waited out the rig's sim_stale_ms from the
  // last usable sample.
  EXPECT_GE(double(shm::monotonic_ns() - last_healthy_tick_ns) * 1e-6, rig.devices[0].watchdogs.sim_stale_ms);
  EXPECT_EQ(attachment.reader.check_liveness(shm::monotonic_ns(), 0), shm::WriterStatus::corrupt)
      << "the supervisor's check sees it and looks for a new segment";
  sim.close();
}

}  // namespace

TEST(LoopCorruptSim, SimSegmentWithARewrittenHeaderFaultsLikeADeadSim) {
  expect_spoiled_sim_faults_like_a_dead_one("corrupt-header", [](shm::LatestWriter& sim) {
    const_cast<shm::Segment&>(sim.segment()).writable_header().slot_count = 0;
  });
}

TEST(LoopCorruptSim, SimSegmentShrunkUnderTheLoopFaultsLikeADeadSim) {
  expect_spoiled_sim_faults_like_a_dead_one("corrupt-shrunk", [](shm::LatestWriter& sim) {
    // To the header's 128 bytes: the header page and its values stay, every slot page is gone.
    int fd = ::shm_open(sim.segment().name().c_str(), O_RDWR, 0);
    ASSERT_GE(fd, 0);
    ASSERT_EQ(::ftruncate(fd, sizeof(shm::SegmentHeader)), 0);
    ::close(fd);
  });
}
