// The read-only observer behind haptic-dashboard: it follows the parts as they start, stop and
// restart in any order, reads what the loop traced and the sim published, and survives any
// content a writer puts in a segment.
#include <gtest/gtest.h>
#include <sys/mman.h>
#include <unistd.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <string>

#include "hapfluid/rt/stack_observer.hpp"
#include "hapfluid/safety/flags.hpp"

using namespace hapfluid;
using namespace hapfluid::shm;

namespace {

// Removes the test's segments when the test ends, passed or not (declared before the writers, it
// goes after them; a writer going out of scope unmaps its segment but leaves the name).
struct SegmentsRemovedAtEnd {
  std::string prefix;
  ~SegmentsRemovedAtEnd() {
    for (ChannelKind k : {ChannelKind::trace, ChannelKind::device_states, ChannelKind::sim_samples, ChannelKind::particles})
      ::shm_unlink(segment_name(prefix, k).c_str());
  }
};

std::string test_prefix(const char* what) { return "hapfluid-observer-test-" + std::to_string(::getpid()) + "-" + what; }

TraceRecord trace_record(std::uint64_t tick, std::uint64_t latency_ns, std::uint32_t faults = 0) {
  TraceRecord r{};
  r.tick = tick;
  r.scheduled_ns = 1'000'000'000ull + tick * 1'000'000ull;
  r.wake_ns = r.scheduled_ns + latency_ns;
  r.send_ns = r.wake_ns + 20'000;
  r.device_count = 1;
  r.devices[0].faults = faults;
  r.devices[0].fresh = 1;
  r.devices[0].force_n[2] = 2.0f;
  return r;
}

}  // namespace

TEST(StackObserver, WaitsForEachPartAndFollowsItsRecords) {
  const std::string prefix = test_prefix("follow");
  rt::StackObserver observer(prefix);
  observer.poll(monotonic_ns());
  EXPECT_EQ(observer.loop().status, "waiting");
  EXPECT_EQ(observer.sim().status, "waiting");
  EXPECT_EQ(observer.states_status(), "waiting");

  SegmentsRemovedAtEnd removed{prefix};
  auto trace = RingWriter::create(segment_name(prefix, ChannelKind::trace), ChannelKind::trace, sizeof(TraceRecord), 4096);
  for (std::uint64_t t = 1; t <= 1000; ++t) trace.push(trace_record(t, t <= 990 ? 20'000 : 400'000));
  // Tick 1001 sent its commands 1.5 periods after it was due: a deadline miss.
  TraceRecord late = trace_record(1001, 20'000, safety::fault_sim_stale);
  late.send_ns = late.scheduled_ns + 1'500'000;
  trace.push(late);
  auto samples = LatestWriter::create(segment_name(prefix, ChannelKind::sim_samples), ChannelKind::sim_samples,
                                      sizeof(SimSample));
  auto sample = std::make_unique<SimSample>();
  std::snprintf(sample->backend, sizeof sample->backend, "cpu");
  sample->fluid_particles = 5250;
  sample->threads_active = 2;
  sample->device_count = 1;
  sample->couplings[0].valid = 1;
  sample->couplings[0].force_n[2] = 1.5;
  const std::uint64_t t0 = monotonic_ns();
  for (int k = 0; k <= 10; ++k) {
    sample->sequence = 100 + 10 * k;
    sample->sim_time_s = 0.05 * k;           // 10 steps of 5 ms each 0.1 s of wall time:
    sample->publish_ns = t0 + 100'000'000ull * k;  // 100 steps/s at half of real time
    samples.publish(*sample);
    observer.poll(monotonic_ns());
  }
  EXPECT_EQ(observer.loop().status, "live");
  EXPECT_EQ(observer.loop().tick, 1001u);
  EXPECT_EQ(observer.loop().records, 1001u);
  EXPECT_EQ(observer.loop().deadline_misses, 1u);
  EXPECT_EQ(observer.loop().latency.count(), 1001u);
  EXPECT_EQ(observer.loop().latency.percentile_us(0.5), 21.0);   // the 20-21 us bin
  EXPECT_EQ(observer.loop().latency.percentile_us(0.999), 401.0);
  ASSERT_EQ(observer.devices().size(), 1u);
  EXPECT_EQ(observer.devices()[0].last_fault, "sim_stale");
  EXPECT_EQ(observer.devices()[0].fresh_share, 1.0);
  EXPECT_EQ(observer.devices()[0].command_force_n[2], 2.0f);
  EXPECT_TRUE(observer.devices()[0].sim_valid);
  EXPECT_EQ(observer.devices()[0].sim_force_n[2], 1.5);
  EXPECT_EQ(observer.sim().backend, "cpu");
  EXPECT_EQ(observer.sim().fluid_particles, 5250u);
  EXPECT_NEAR(observer.sim().steps_per_s, 100.0, 1e-6);
  EXPECT_NEAR(observer.sim().real_time_factor, 0.5, 1e-6);
  const std::string json = observer.snapshot_json(monotonic_ns());
  EXPECT_NE(json.find("\"backend\":\"cpu\""), std::string::npos) << json;
  EXPECT_NE(json.find("\"last_fault\":\"sim_stale\""), std::string::npos) << json;

  // The sim stops: said, its couplings no longer shown; a new sim is attached and counted anew.
  samples.close();
  observer.poll(monotonic_ns());
  EXPECT_NE(observer.sim().status, "live");
  EXPECT_FALSE(observer.devices()[0].sim_valid);
  auto again = LatestWriter::create(segment_name(prefix, ChannelKind::sim_samples), ChannelKind::sim_samples,
                                    sizeof(SimSample));
  sample->sequence = 1;
  sample->publish_ns = monotonic_ns();
  again.publish(*sample);
  observer.poll(monotonic_ns());
  EXPECT_EQ(observer.sim().status, "live");
  EXPECT_EQ(observer.sim().sequence, 1u);

  // The loop restarts: a new run, with statistics of its own.
  trace.close();
  observer.poll(monotonic_ns());
  EXPECT_NE(observer.loop().status, "live");
  auto trace2 = RingWriter::create(segment_name(prefix, ChannelKind::trace), ChannelKind::trace, sizeof(TraceRecord), 4096);
  trace2.push(trace_record(1, 30'000));
  observer.poll(monotonic_ns());
  EXPECT_EQ(observer.loop().status, "live");
  EXPECT_EQ(observer.loop().records, 1u);
  EXPECT_EQ(observer.loop().deadline_misses, 0u);
}

TEST(StackObserver, HostileContentIsShownSafelyNeverTrusted) {
  // Non-finite wrenches, a device name without its NUL and with control bytes, device counts
  // beyond the layout, a backend name filling its field: the observer clamps and cleans them.
  const std::string prefix = test_prefix("hostile");
  SegmentsRemovedAtEnd removed{prefix};
  auto states = LatestWriter::create(segment_name(prefix, ChannelKind::device_states), ChannelKind::device_states,
                                     sizeof(DeviceStatesRecord));
  auto samples = LatestWriter::create(segment_name(prefix, ChannelKind::sim_samples), ChannelKind::sim_samples,
                                      sizeof(SimSample));
  auto trace = RingWriter::create(segment_name(prefix, ChannelKind::trace), ChannelKind::trace, sizeof(TraceRecord), 64);
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  DeviceStatesRecord rec{};
  rec.device_count = 0xffffffffu;
  std::memset(rec.devices[0].name, '\x07', sizeof rec.devices[0].name);
  rec.devices[0].force_n[0] = nan, rec.devices[0].torque_nm[1] = inf, rec.devices[0].position_m[2] = -inf;
  states.publish(rec);
  auto sample = std::make_unique<SimSample>();
  std::memset(sample->backend, 'x', sizeof sample->backend);
  sample->device_count = 1000;
  sample->couplings[0].force_n[0] = nan;
  sample->sim_time_s = inf;
  sample->publish_ns = monotonic_ns() + 1'000'000'000'000ull;  // stamped in the future
  samples.publish(*sample);
  TraceRecord r = trace_record(1, 0);
  r.device_count = 77;
  r.wake_ns = r.scheduled_ns - 5;  // woke "before" it was due
  r.devices[0].force_n[0] = std::numeric_limits<float>::quiet_NaN();
  trace.push(r);
  rt::StackObserver observer(prefix);
  observer.poll(monotonic_ns());
  ASSERT_EQ(observer.devices().size(), static_cast<std::size_t>(kMaxDevices));
  const rt::ObservedDevice& d = observer.devices()[0];
  EXPECT_EQ(d.name, std::string(kDeviceNameBytes, '?'));
  EXPECT_EQ(d.hand_force_n[0], 0.0);
  EXPECT_EQ(d.hand_torque_nm[1], 0.0);
  EXPECT_EQ(d.position_m[2], 0.0);
  EXPECT_EQ(d.sim_force_n[0], 0.0);
  EXPECT_EQ(d.command_force_n[0], 0.0f);
  EXPECT_EQ(observer.sim().backend, std::string(15, 'x'));
  EXPECT_EQ(observer.sim().sim_time_s, 0.0);
  EXPECT_EQ(observer.sim().sample_age_ms, 0.0);
  EXPECT_EQ(observer.loop().latency.percentile_us(1.0), 1.0);
  const std::string json = observer.snapshot_json(monotonic_ns());  // valid JSON, no NaN in it
  EXPECT_EQ(json.find("nan"), std::string::npos);
  EXPECT_EQ(json.find("inf"), std::string::npos);
}
