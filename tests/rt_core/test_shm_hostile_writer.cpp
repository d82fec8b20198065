// No content of a segment may crash a reader. haptic-rt maps segments that other processes write
// (sim_samples); a broken or hostile writer that rewrites its header, shrinks its object or fills
// it with garbage must leave the reader running with a clear result: attach refuses it with the
// reason, and a segment spoiled after attach reads as `corrupt`, which its users treat as a dead
// writer. Each test runs the spoiling and the reads in this process: a crash fails the binary.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/mman.h>
#include <unistd.h>

#include <cstring>
#include <random>
#include <string>

#include "hapfluid/shm/channel.hpp"

using namespace hapfluid::shm;

namespace {

std::string unique_name(const char* what) { return "/hapfluid-test-" + std::to_string(::getpid()) + "." + what; }

// A sim_samples-sized record: 4 slots of 2.5 KB span three 4 KiB pages, so shrinking the object to
// its header leaves slot pages that no longer exist (the case that raises SIGBUS).
constexpr std::uint64_t kRecordBytes = sizeof(SimSample);

struct Attached {
  std::string name;
  LatestWriter writer;
  LatestReader reader;
  SegmentHeader& shared_header() { return const_cast<Segment&>(writer.segment()).writable_header(); }
};

// A live channel with one record published, and a reader that attached while it was sound.
Attached attached_channel(const char* what) {
  Attached a;
  a.name = unique_name(what);
  a.writer = LatestWriter::create(a.name, ChannelKind::sim_samples, kRecordBytes, 4);
  SimSample sample{};
  sample.sequence = 1;
  a.writer.publish(sample);
  a.reader = LatestReader::attach(a.name, ChannelKind::sim_samples, kRecordBytes);
  SimSample out{};
  EXPECT_EQ(a.reader.try_read(out), ReadResult::ok);
  return a;
}

void expect_corrupt(const LatestReader& reader) {
  SimSample out{};
  EXPECT_EQ(reader.try_read(out), ReadResult::corrupt);
  EXPECT_EQ(reader.status(monotonic_ns(), 0), WriterStatus::corrupt);
  EXPECT_EQ(reader.check_liveness(monotonic_ns(), 0), WriterStatus::corrupt);
}

std::string attach_error(const std::string& name) {
  try {
    LatestReader reader = LatestReader::attach(name, ChannelKind::sim_samples, kRecordBytes);
    SimSample out{};
    reader.try_read(out);  // accepted: reading it must be safe too
    return {};
  } catch (const ShmError& e) {
    return e.what();
  }
}

}  // namespace

TEST(ShmHostileWriter, SlotCountRewrittenToZeroAfterAttachReadsAsCorrupt) {
  // The reader once took slot_count from shared memory on every read: 0 divided by zero (SIGFPE).
  Attached a = attached_channel("slots0");
  a.shared_header().slot_count = 0;
  a.shared_header().published.fetch_add(1);
  expect_corrupt(a.reader);
  a.writer.close();
}

TEST(ShmHostileWriter, SlotBytesEnlargedAfterAttachReadsAsCorrupt) {
  // A slot size of 1 TiB put slot 1 far outside the 10 KB mapping (SIGSEGV).
  Attached a = attached_channel("slotbytes");
  a.shared_header().slot_bytes = 1ull << 40;
  a.shared_header().published.fetch_add(1);
  expect_corrupt(a.reader);
  a.writer.close();
}

TEST(ShmHostileWriter, ObjectShrunkAfterAttachReadsAsCorruptInsteadOfSigbus) {
  // ftruncate to the header's 128 bytes: every slot page is gone and touching one raises SIGBUS.
  // The header page and its values stay, so only the shrink itself can tell the reader.
  Attached a = attached_channel("shrunk");
  int fd = ::shm_open(a.name.c_str(), O_RDWR, 0);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(::ftruncate(fd, sizeof(SegmentHeader)), 0);
  ::close(fd);
  expect_corrupt(a.reader);
  // The writer's own mapping is guarded the same way: publishing into the lost pages is harmless.
  a.writer.publish(SimSample{});
  a.writer.close();
}

TEST(ShmHostileWriter, GarbageOverTheWholeSegmentAfterAttachReadsAsCorrupt) {
  Attached a = attached_channel("garbage");
  std::mt19937_64 random(7);
  auto* bytes = reinterpret_cast<std::uint64_t*>(&a.shared_header());
  for (std::uint64_t i = 0; i < a.writer.segment().layout().total_bytes / 8; ++i) bytes[i] = random();
  expect_corrupt(a.reader);
  a.writer.close();
}

TEST(ShmHostileWriter, SizesThatOnlyAddUpByOverflowAreRefusedAtAttach) {
  // 2 slots of 2^63 + 5120 bytes "add up" to the object's 10 KB in 64-bit arithmetic; a reader
  // that accepted it mapped slot 1 at an address 2^63 bytes away.
  Attached a = attached_channel("overflow");
  const std::uint64_t slot_area = a.writer.segment().layout().total_bytes - sizeof(SegmentHeader);
  a.shared_header().slot_count = 2;
  a.shared_header().slot_bytes = (1ull << 63) + slot_area / 2;
  const std::string error = attach_error(a.name);
  EXPECT_NE(error.find("inconsistent sizes"), std::string::npos) << error;
  EXPECT_NE(error.find("slot_bytes"), std::string::npos) << error;
  a.writer.close();
}

TEST(ShmHostileWriter, RecordSizeThatOnlyFitsItsSlotByOverflowIsRefusedAtAttach) {
  // A record size of 2^64 - 1 padded to whole words wrapped to 0 and "fit" any slot; a reader that
  // takes the writer's record size (haptic-render's particles, payload 0) then sized its copy
  // from it. Attach must refuse it like any record larger than its slot.
  const std::string name = unique_name("payload");
  LatestWriter writer = LatestWriter::create(name, ChannelKind::particles, particle_frame_bytes(4), 2);
  const_cast<Segment&>(writer.segment()).writable_header().payload_bytes = ~0ull;
  try {
    LatestReader::attach(name, ChannelKind::particles, 0);
    ADD_FAILURE() << "a record of 2^64 - 1 bytes in a 1 KB slot was accepted";
  } catch (const ShmError& e) {
    EXPECT_NE(std::string(e.what()).find("payload_bytes 18446744073709551615 does not fit a 1088-byte slot"),
              std::string::npos)
        << e.what();
  }
  writer.close();
}

TEST(ShmHostileWriter, SlotCountZeroAndTruncatedObjectAreRefusedAtAttachWithTheReason) {
  Attached a = attached_channel("attach0");
  a.shared_header().slot_count = 0;
  std::string error = attach_error(a.name);
  EXPECT_NE(error.find("slot_count 0"), std::string::npos) << error;
  a.shared_header().slot_count = 4;
  int fd = ::shm_open(a.name.c_str(), O_RDWR, 0);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(::ftruncate(fd, sizeof(SegmentHeader) + 4096), 0);
  ::close(fd);
  error = attach_error(a.name);
  EXPECT_NE(error.find("but the object has 4224"), std::string::npos) << error;
  a.writer.close();
}

TEST(ShmHostileWriter, AttachAcceptsExactlyTheHeadersWhoseSlotsTileTheObject) {
  // 3000 headers with a valid identity (magic, ABI, kind) and a random published count: a third
  // whose slots tile the 10 KB object exactly (1, 2 or 4 slots), a third one 64-byte step off, a
  // third random. Attach accepts exactly the first kind, and reads from those stay inside the
  // mapping whatever they say. Fixed seed: the same headers every run.
  Attached a = attached_channel("fuzz");
  const SegmentLayout real = a.writer.segment().layout();
  const std::uint64_t slot_area = real.total_bytes - sizeof(SegmentHeader);
  std::mt19937_64 random(2026);
  for (int i = 0; i < 3000; ++i) {
    SegmentHeader& h = a.shared_header();
    const std::uint32_t slots = 1u << (random() % 3);
    h.total_bytes = real.total_bytes;
    h.slot_count = slots;
    h.slot_bytes = slot_area / slots;
    const int kind = i % 3;
    if (kind == 1) h.slot_bytes += random() % 2 ? 64 : -64;
    if (kind == 2) {
      h.slot_count = static_cast<std::uint32_t>(random());
      h.slot_bytes = random();
      h.total_bytes = random() % 2 ? real.total_bytes : random();
    }
    h.published.store(random());
    const std::string error = attach_error(a.name);
    if (kind == 0) {
      EXPECT_EQ(error, "") << "header " << i << ": " << slots << " slots";
    } else if (kind == 1) {
      EXPECT_NE(error.find("inconsistent sizes"), std::string::npos) << "header " << i << ": " << error;
    }
  }
  a.writer.close();
}

TEST(ShmHostileWriter, RingRewrittenAfterAttachStopsDeliveringAndReadsAsCorrupt) {
  // haptic-trace reads the trace ring the same way; a rewritten ring must not be walked.
  const std::string name = unique_name("ring");
  RingWriter writer = RingWriter::create(name, ChannelKind::trace, sizeof(TraceRecord), 64);
  RingAttachment attachment = RingAttachment::attach(name, ChannelKind::trace, sizeof(TraceRecord));
  RingReader reader = attachment.reader_from_oldest();
  writer.push(TraceRecord{});
  const_cast<Segment&>(writer.segment()).writable_header().slot_bytes = 1ull << 40;
  writer.push(TraceRecord{});
  TraceRecord out{};
  EXPECT_FALSE(reader.next(out));
  EXPECT_EQ(attachment.status(monotonic_ns(), 0), WriterStatus::corrupt);
  writer.close();
}
