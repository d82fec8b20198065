// The shared-memory contract (docs/architecture.md, Contracts): ownership, header validation, dead/stale/closed/
// restarted writer detection and the ring's loss accounting. Each test uses its own segment name.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <fcntl.h>
#include <grp.h>
#include <sys/mman.h>
#include <unistd.h>

#include <chrono>
#include <cstring>
#include <thread>

#include "hapfluid/shm/channel.hpp"

using namespace hapfluid::shm;

namespace {

std::string unique_name(const char* what) {
  return "/hapfluid-test-" + std::to_string(::getpid()) + "." + what;
}

struct Sample {
  std::uint64_t value;
  double payload[5];
};

// Runs `body` in a child process that exits without any clean-up, like a crash.
pid_t run_child(auto body) {
  pid_t pid = ::fork();
  if (pid == 0) {
    body();
    ::_exit(0);
  }
  return pid;
}

void wait_child(pid_t pid) {
  int status = 0;
  ::waitpid(pid, &status, 0);
}

}  // namespace

TEST(ShmChannel, ReaderSeesTheNewestRecordAndItsGeneration) {
  auto name = unique_name("latest");
  auto writer = LatestWriter::create(name, ChannelKind::sim_samples, sizeof(Sample));
  auto reader = LatestReader::attach(name, ChannelKind::sim_samples, sizeof(Sample));
  Sample out{};
  EXPECT_EQ(reader.try_read(out), ReadResult::no_data);
  for (std::uint64_t i = 1; i <= 10; ++i) writer.publish(Sample{i * 7, {1, 2, 3, 4, 5}});
  std::uint64_t generation = 0;
  ASSERT_EQ(reader.try_read(out, &generation), ReadResult::ok);
  EXPECT_EQ(out.value, 70u);
  EXPECT_EQ(generation, 10u);
  EXPECT_EQ(reader.status(monotonic_ns(), 1'000'000'000), WriterStatus::live);
  writer.close();
}

// The writer stopped between filling a slot and publishing it: `generation` is in its slot, and
// `published` still names the record before it. Written as LatestWriter::publish writes a slot.
void fill_slot_without_publishing(const LatestWriter& writer, std::uint64_t generation, const Sample& record) {
  std::byte* slot = writer.segment().slot(generation);
  auto& header = *reinterpret_cast<SlotHeader*>(slot);
  const std::uint64_t sequence = header.sequence.load();
  header.sequence.store(sequence + 1);
  header.generation.store(generation);
  std::memcpy(slot + kSlotHeaderBytes, &record, sizeof record);
  header.sequence.store(sequence + 2);
}

TEST(ShmChannel, LatestReadParkedWhileTheWriterLapsTheRingNeverGoesBackwards) {
  // A reader loads published = 1 and is descheduled; the writer publishes 2 and 3 on a 3-slot
  // ring and has filled slot 1 % 3 with record 4 but not yet published it. Copying record 4 now
  // and record 3 on the next read would hand the loop an older sim sample after a newer one.
  // The reader's two steps (load published, copy that generation) are driven one by one here.
  constexpr std::uint32_t kSlots = 3;
  auto name = unique_name("lapped");
  auto writer = LatestWriter::create(name, ChannelKind::sim_samples, sizeof(Sample), kSlots);
  auto reader = LatestReader::attach(name, ChannelKind::sim_samples, sizeof(Sample));
  writer.publish(Sample{1, {}});
  const std::uint64_t parked = reader.published();
  ASSERT_EQ(parked, 1u);
  for (std::uint64_t value = 2; value <= kSlots; ++value) writer.publish(Sample{value, {}});
  fill_slot_without_publishing(writer, parked + kSlots, Sample{parked + kSlots, {}});

  Sample out{};
  EXPECT_EQ(reader.read_generation(parked, &out, sizeof out), ReadResult::overwritten)
      << "the parked reader copied record " << out.value << " in place of record " << parked;
  std::uint64_t generation = 0;
  ASSERT_EQ(reader.try_read(out, &generation), ReadResult::ok);
  EXPECT_EQ(generation, kSlots) << "the newest published record, not the unpublished one";
  EXPECT_EQ(out.value, kSlots);
  writer.close();
}

TEST(ShmChannel, SegmentIsCreatedWithMode0640AndRemovedOnCleanClose) {
  // Mode 0640: only the writer may write; the rig's service group may read, nobody else.
  auto name = unique_name("mode");
  auto writer = LatestWriter::create(name, ChannelKind::device_states, 64);
  struct stat st {};
  ASSERT_EQ(::stat(("/dev/shm" + name).c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0640u);
  auto reader = LatestReader::attach(name, ChannelKind::device_states, 64);
  writer.close();
  EXPECT_NE(::stat(("/dev/shm" + name).c_str(), &st), 0) << "a clean stop leaves no segment behind";
  EXPECT_EQ(reader.status(monotonic_ns(), 0), WriterStatus::closed);
}

TEST(ShmChannel, SegmentBelongsToTheConfiguredGroup) {
  // rt.shm.group is the group that may read the channel (never write it: mode 0640).
  struct group* g = ::getgrgid(::getgid());
  ASSERT_NE(g, nullptr);
  auto name = unique_name("owned");
  WriterOptions options;
  options.group = g->gr_name;
  auto writer = LatestWriter::create(name, ChannelKind::device_states, 64, 4, options);
  struct stat st {};
  ASSERT_EQ(::stat(("/dev/shm" + name).c_str(), &st), 0);
  EXPECT_EQ(st.st_gid, g->gr_gid);
  EXPECT_EQ(st.st_mode & 0777, 0640u);
  writer.close();
}

TEST(ShmChannel, UnknownGroupIsRefusedWithItsName) {
  auto name = unique_name("group");
  try {
    WriterOptions options;
    options.group = "no-such-group-hapfluid";
    LatestWriter::create(name, ChannelKind::device_states, 64, 4, options);
    FAIL() << "expected ShmError";
  } catch (const ShmError& e) {
    EXPECT_NE(std::string(e.what()).find("no-such-group-hapfluid"), std::string::npos) << e.what();
  }
}

TEST(ShmChannel, MissingSegmentSaysTheWriterHasNotStarted) {
  try {
    LatestReader::attach(unique_name("missing"), ChannelKind::sim_samples, sizeof(Sample));
    FAIL() << "expected ShmError";
  } catch (const ShmError& e) {
    EXPECT_NE(std::string(e.what()).find("has not started"), std::string::npos) << e.what();
  }
}

TEST(ShmChannel, VersionKindAndSizeMismatchesAreRefusedClearly) {
  auto name = unique_name("mismatch");
  auto writer = LatestWriter::create(name, ChannelKind::sim_samples, sizeof(Sample));
  auto expect_error = [&](ChannelKind kind, std::uint64_t bytes, const char* words) {
    try {
      LatestReader::attach(name, kind, bytes);
      ADD_FAILURE() << "expected ShmError containing " << words;
    } catch (const ShmError& e) {
      EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
    }
  };
  expect_error(ChannelKind::sim_samples, sizeof(Sample) + 8, "record size");
  expect_error(ChannelKind::particles, sizeof(Sample), "\"particles\" was expected");
  // A writer from another build: its header declares another ABI version.
  const_cast<Segment&>(writer.segment()).writable_header().abi_version = kAbiVersion + 41;
  expect_error(ChannelKind::sim_samples, sizeof(Sample), "ABI version");
  writer.close();
}

TEST(ShmChannel, ForeignSegmentIsNotMistakenForAChannel) {
  auto name = unique_name("foreign");
  int fd = ::shm_open(name.c_str(), O_RDWR | O_CREAT | O_EXCL, 0600);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(::ftruncate(fd, 4096), 0);
  ::close(fd);
  try {
    LatestReader::attach(name, ChannelKind::sim_samples, sizeof(Sample));
    ADD_FAILURE() << "expected ShmError";
  } catch (const ShmError& e) {
    EXPECT_NE(std::string(e.what()).find("bad magic"), std::string::npos) << e.what();
  }
  ::shm_unlink(name.c_str());
}

TEST(ShmChannel, DeadWriterIsDetectedAndItsLeftoverSegmentReplaced) {
  // A sim that crashes leaves its segment behind; readers must notice, and the next sim must be
  // able to start without manual clean-up (a stale segment from a crashed run).
  auto name = unique_name("dead");
  pid_t child = run_child([&] {
    auto writer = LatestWriter::create(name, ChannelKind::sim_samples, sizeof(Sample));
    writer.publish(Sample{1, {}});
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    // exits without close(): a crash
  });
  LatestReader reader;
  for (int i = 0; i < 200 && !reader.valid(); ++i) {
    try {
      reader = LatestReader::attach(name, ChannelKind::sim_samples, sizeof(Sample));
    } catch (const ShmError&) {
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
  }
  ASSERT_TRUE(reader.valid());
  EXPECT_EQ(reader.check_liveness(monotonic_ns(), 0), WriterStatus::live);
  wait_child(child);
  // 50 ms without a heartbeat is stale; the process being gone is dead.
  std::this_thread::sleep_for(std::chrono::milliseconds(60));
  EXPECT_EQ(reader.status(monotonic_ns(), 50'000'000), WriterStatus::stale);
  EXPECT_EQ(reader.check_liveness(monotonic_ns(), 50'000'000), WriterStatus::dead);

  // Restart: a new writer replaces the leftover, and says so (a crashed predecessor is never
  // silent); the old mapping reports it, a re-attach sees the new incarnation and its data.
  testing::internal::CaptureStderr();
  auto restarted = LatestWriter::create(name, ChannelKind::sim_samples, sizeof(Sample));
  const std::string said = testing::internal::GetCapturedStderr();
  EXPECT_NE(said.find("shm " + name + ": replacing the segment left by pid " + std::to_string(child)), std::string::npos)
      << said;
  restarted.publish(Sample{99, {}});
  EXPECT_EQ(reader.check_liveness(monotonic_ns(), 50'000'000), WriterStatus::replaced);
  auto fresh = LatestReader::attach(name, ChannelKind::sim_samples, sizeof(Sample));
  EXPECT_NE(fresh.segment().layout().incarnation, reader.segment().layout().incarnation);
  Sample out{};
  ASSERT_EQ(fresh.try_read(out), ReadResult::ok);
  EXPECT_EQ(out.value, 99u);
  restarted.close();
}

TEST(ShmChannel, SecondWriterIsRefusedWhileTheFirstIsAlive) {
  // Single writer: a second sim started by mistake must not scribble over the first one's samples.
  auto name = unique_name("owner");
  int ready[2];
  ASSERT_EQ(::pipe(ready), 0);
  pid_t child = run_child([&] {
    auto writer = LatestWriter::create(name, ChannelKind::sim_samples, sizeof(Sample));
    char c = 1;
    (void)!::write(ready[1], &c, 1);
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
    writer.close();
  });
  char c;
  ASSERT_EQ(::read(ready[0], &c, 1), 1);
  try {
    LatestWriter::create(name, ChannelKind::sim_samples, sizeof(Sample));
    ADD_FAILURE() << "expected ShmError";
  } catch (const ShmError& e) {
    EXPECT_NE(std::string(e.what()).find("pid " + std::to_string(child)), std::string::npos) << e.what();
  }
  wait_child(child);
}

TEST(ShmChannel, RingCountsRecordsLostToASlowReader) {
  // The trace writer never waits for haptic-trace; what a slow reader misses is counted.
  auto name = unique_name("ring");
  auto writer = RingWriter::create(name, ChannelKind::trace, sizeof(Sample), 64);
  auto attachment = RingAttachment::attach(name, ChannelKind::trace, sizeof(Sample));
  RingReader reader = attachment.reader_from_oldest();
  for (std::uint64_t i = 0; i < 200; ++i) writer.push(Sample{i, {}});
  Sample out{};
  std::uint64_t expected = 200 - 64, read = 0;
  while (reader.next(out)) {
    EXPECT_EQ(out.value, expected++);
    ++read;
  }
  EXPECT_EQ(read, 64u);
  EXPECT_EQ(reader.lost(), 136u);
  EXPECT_FALSE(reader.next(out)) << "caught up";
  writer.push(Sample{200, {}});
  ASSERT_TRUE(reader.next(out));
  EXPECT_EQ(out.value, 200u);
  writer.close();
}

TEST(ShmChannel, RingSizeMustBeAPowerOfTwo) {
  EXPECT_THROW(RingWriter::create(unique_name("ring3"), ChannelKind::trace, 8, 100), ShmError);
}

TEST(ShmChannel, VariableSizeParticleFrameRoundTrips) {
  // The particle channel's record size is chosen by the sim at creation (max particle count);
  // the renderer learns it from the header.
  auto name = unique_name("particles");
  const std::uint32_t max_particles = 1000;
  std::vector<std::byte> frame(particle_frame_bytes(max_particles));
  auto* header = reinterpret_cast<ParticleFrameHeader*>(frame.data());
  header->max_particles = max_particles;
  header->particle_count = 3;
  auto* particles = reinterpret_cast<ParticleRecord*>(frame.data() + sizeof(ParticleFrameHeader));
  particles[2].position_m[1] = 0.25f;
  auto writer = LatestWriter::create(name, ChannelKind::particles, frame.size(), 3);
  writer.publish(frame.data(), frame.size());
  auto reader = LatestReader::attach(name, ChannelKind::particles, 0);
  ASSERT_EQ(reader.segment().layout().payload_bytes, particle_frame_bytes(max_particles));
  std::vector<std::byte> copy(reader.segment().layout().payload_bytes);
  ASSERT_EQ(reader.try_read(copy.data(), copy.size()), ReadResult::ok);
  EXPECT_EQ(reinterpret_cast<ParticleFrameHeader*>(copy.data())->particle_count, 3u);
  EXPECT_EQ(reinterpret_cast<ParticleRecord*>(copy.data() + sizeof(ParticleFrameHeader))[2].position_m[1], 0.25f);
  writer.close();
}
