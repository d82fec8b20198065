// The live frame source reads the simulator's particles channel without ever blocking it: it
// waits quietly for a writer, takes each new frame once, follows a restarted simulator, and a
// dead one never stops the renderer.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cstring>
#include <vector>

#include "hapfluid/render/shm_source.hpp"
#include "hapfluid/shm/channel.hpp"
#include "hapfluid/shm/layouts.hpp"

using namespace hapfluid;
using namespace hapfluid::render;

namespace {

std::string unique_prefix(const char* what) { return "hapfluid-test-render-" + std::to_string(::getpid()) + "-" + what; }

// A particles-channel writer as the simulator holds it: header + max_particles records.
struct SimWriter {
  shm::LatestWriter writer;
  std::vector<std::byte> frame;
  std::uint32_t max_particles;

  SimWriter(const std::string& prefix, std::uint32_t max) : max_particles(max) {
    frame.resize(shm::particle_frame_bytes(max));
    writer = shm::LatestWriter::create(shm::segment_name(prefix, shm::ChannelKind::particles), shm::ChannelKind::particles,
                                       frame.size());
  }
  // A writer that goes away without close() leaves its segment as a crashed simulator would
  // (channel.hpp): the tests' writers stop cleanly and leave nothing in /dev/shm.
  ~SimWriter() { writer.close(); }
  SimWriter(const SimWriter&) = delete;
  SimWriter& operator=(const SimWriter&) = delete;
  void publish(std::uint64_t sequence, std::uint32_t count, float x_offset) {
    shm::ParticleFrameHeader h{};
    h.sequence = sequence;
    h.sim_time_s = 0.01 * double(sequence);
    h.publish_ns = shm::monotonic_ns();
    h.particle_count = count;
    h.max_particles = max_particles;
    h.body_count = 1;
    h.particle_radius_m = 0.005f;
    h.bodies[0] = {{0.1, 0.2, 0.3}, {1, 0, 0, 0}};
    std::memcpy(frame.data(), &h, sizeof h);
    for (std::uint32_t i = 0; i < count; ++i) {
      shm::ParticleRecord r{{x_offset + 0.01f * float(i), 0.0f, 0.05f}, 0.0f};
      std::memcpy(frame.data() + sizeof h + i * sizeof r, &r, sizeof r);
    }
    writer.publish(frame.data(), frame.size());
  }
};

SceneDescription one_body_scene() {
  SceneDescription scene;
  scene.bodies.resize(1);
  scene.bodies[0].name = "spoon";
  return scene;
}

ShmSourceOptions fast_options(const std::string& prefix) {
  ShmSourceOptions o;
  o.prefix = prefix;
  o.reattach_interval_s = 0.0;  // look for a writer on every call in tests
  return o;
}

}  // namespace

TEST(ShmSource, WaitsQuietlyForTheSimulator) {
  ShmSource source(one_body_scene(), fast_options(unique_prefix("wait")));
  Frame frame;
  EXPECT_EQ(source.next_frame(frame), FrameStatus::unchanged);
  EXPECT_EQ(source.writer_status(), shm::WriterStatus::not_attached);
}

TEST(ShmSource, TakesEachNewFrameOnceWithItsParticlesAndBodyPoses) {
  const std::string prefix = unique_prefix("frames");
  SimWriter sim(prefix, 1000);
  ShmSource source(one_body_scene(), fast_options(prefix));
  Frame frame;
  sim.publish(7, 300, 0.0f);
  ASSERT_EQ(source.next_frame(frame), FrameStatus::new_frame);
  EXPECT_EQ(frame.fluid_m.size(), 300u);  // only the meaningful records, not max_particles
  EXPECT_FLOAT_EQ(frame.fluid_m[299].x, 2.99f);
  EXPECT_EQ(frame.index, 7u);
  ASSERT_EQ(frame.body_poses.size(), 1u);
  EXPECT_FLOAT_EQ(frame.body_poses[0].position_m.z, 0.3f);
  EXPECT_EQ(source.next_frame(frame), FrameStatus::unchanged) << "the same frame is not drawn twice";
  sim.publish(8, 10, 1.0f);
  ASSERT_EQ(source.next_frame(frame), FrameStatus::new_frame);
  EXPECT_EQ(frame.fluid_m.size(), 10u);
  EXPECT_FLOAT_EQ(frame.fluid_m[0].x, 1.0f);
}

TEST(ShmSource, FollowsARestartedSimulator) {
  const std::string prefix = unique_prefix("restart");
  ShmSource source(one_body_scene(), fast_options(prefix));
  Frame frame;
  {
    SimWriter first(prefix, 100);
    first.publish(1, 50, 0.0f);
    ASSERT_EQ(source.next_frame(frame), FrameStatus::new_frame);
    first.writer.close();  // the simulator stops (or is restarted)
  }
  EXPECT_EQ(source.next_frame(frame), FrameStatus::unchanged);
  SimWriter second(prefix, 2000);  // a new run may size its frames differently
  second.publish(1, 1500, 0.5f);
  FrameStatus status = FrameStatus::unchanged;
  for (int i = 0; i < 5 && status != FrameStatus::new_frame; ++i) status = source.next_frame(frame);
  ASSERT_EQ(status, FrameStatus::new_frame);
  EXPECT_EQ(frame.fluid_m.size(), 1500u);
  EXPECT_FLOAT_EQ(frame.fluid_m[0].x, 0.5f);
}

TEST(ShmSource, RefusesASegmentThatIsNotParticleFrames) {
  const std::string prefix = unique_prefix("foreign");
  // Right channel kind, but a payload no particle frame can have.
  auto writer = shm::LatestWriter::create(shm::segment_name(prefix, shm::ChannelKind::particles),
                                          shm::ChannelKind::particles, 24);
  std::byte junk[24] = {};
  writer.publish(junk, sizeof junk);
  ShmSource source(one_body_scene(), fast_options(prefix));
  Frame frame;
  EXPECT_EQ(source.next_frame(frame), FrameStatus::unchanged);
  writer.close();
}
