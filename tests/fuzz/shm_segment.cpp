// Fuzz target: a shared-memory segment written by a broken or hostile writer, read by the real
// readers of rt_core's hapfluid_shm the way haptic-rt, haptic-sim, haptic-render (latest-value
// channels) and haptic-trace (the trace ring, drained to CSV) read theirs. The input is what the
// "writer" puts into one real POSIX shm object:
//   [u16 LE n][n bytes: the object when the reader attaches][the rest: the object afterwards]
// The reader attaches as the channel the header names and reads everything a user of that channel
// reads. When there is a second image, the object is then rewritten, shrunk or grown to it while
// still mapped, and read again. The contract (docs/architecture.md, "No segment can crash a
// reader"): no content crashes a reader, and after attach the segment reads as corrupt exactly
// when its header's layout changed or its object lost pages.
#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstddef>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "fuzz_target.h"
#include "hapfluid/rt/trace_csv.hpp"
#include "hapfluid/shm/channel.hpp"

using namespace hapfluid::shm;

namespace {

// One object for the whole run, rewritten per input (no file created per execution).
struct Object {
  std::string name = "/hapfluid-fuzz-" + std::to_string(::getpid()) + ".segment";
  int fd = -1;
  std::FILE* csv = nullptr;  // haptic-trace's output, discarded

  Object() {
    ::shm_unlink(name.c_str());  // a leftover of a crashed run under a reused pid
    fd = ::shm_open(name.c_str(), O_RDWR | O_CREAT | O_EXCL, 0600);
    if (fd < 0 || ::fchmod(fd, 0640) != 0) {  // the mode a writer gives its segments
      std::perror(name.c_str());
      std::exit(1);
    }
    csv = std::fopen("/dev/null", "w");
  }
  ~Object() {
    ::shm_unlink(name.c_str());
    ::close(fd);
    if (csv) std::fclose(csv);
  }
  static Object& object() {
    static Object o;
    return o;
  }
  void write(const std::uint8_t* bytes, std::size_t size) const {
    if (::ftruncate(fd, static_cast<off_t>(size)) != 0 ||
        (size > 0 && ::pwrite(fd, bytes, size, 0) != static_cast<ssize_t>(size))) {
      std::perror("fuzz: rewriting the segment");
      std::exit(1);
    }
  }
};

// The header fields attach validates and Segment::intact() compares with its private copy, as a
// reader sees them in an image (bytes past the end of the object read as zero).
struct HeaderFields {
  std::uint64_t magic, slot_bytes, payload_bytes, total_bytes, incarnation;
  std::uint32_t abi_version, header_bytes, channel_kind, slot_count;
  std::int32_t writer_pid;
  bool operator==(const HeaderFields&) const = default;
};

HeaderFields header_of(const std::uint8_t* image, std::size_t size) {
  std::uint8_t bytes[sizeof(SegmentHeader)] = {};
  std::memcpy(bytes, image, size < sizeof bytes ? size : sizeof bytes);
  HeaderFields h;
  auto field = [&](auto& value, std::size_t offset) { std::memcpy(&value, bytes + offset, sizeof value); };
  field(h.magic, offsetof(SegmentHeader, magic));
  field(h.abi_version, offsetof(SegmentHeader, abi_version));
  field(h.channel_kind, offsetof(SegmentHeader, channel_kind));
  field(h.header_bytes, offsetof(SegmentHeader, header_bytes));
  field(h.slot_count, offsetof(SegmentHeader, slot_count));
  field(h.slot_bytes, offsetof(SegmentHeader, slot_bytes));
  field(h.payload_bytes, offsetof(SegmentHeader, payload_bytes));
  field(h.total_bytes, offsetof(SegmentHeader, total_bytes));
  field(h.writer_pid, offsetof(SegmentHeader, writer_pid));
  field(h.incarnation, offsetof(SegmentHeader, incarnation));
  return h;
}

std::size_t pages(std::size_t bytes) {
  static const std::size_t page = static_cast<std::size_t>(::sysconf(_SC_PAGESIZE));
  return (bytes + page - 1) / page;
}

std::uint64_t payload_for(ChannelKind kind) {
  switch (kind) {
    case ChannelKind::device_states: return sizeof(DeviceStatesRecord);
    case ChannelKind::sim_samples: return sizeof(SimSample);
    case ChannelKind::trace: return sizeof(TraceRecord);
    default: return 0;  // particles: the writer picks the frame size, the reader checks it
  }
}

// Everything the users of a latest-value channel call on it; returns its status.
WriterStatus read_latest(const LatestReader& reader, std::vector<std::byte>& buffer) {
  const std::uint64_t bytes = reader.segment().layout().payload_bytes;
  buffer.resize(bytes);
  std::uint64_t generation = 0;
  reader.try_read(buffer.data(), bytes, &generation);
  const std::uint64_t published = reader.published();
  reader.read_generation(published - 1, buffer.data(), bytes);
  reader.read_generation(published + 1, buffer.data(), bytes);
  const std::uint64_t now = monotonic_ns();
  reader.check_liveness(now, 1'000'000'000ull);
  return reader.status(now, 1'000'000'000ull);
}

// haptic-trace: drain from the oldest record into CSV; the flight recorder's read_at.
WriterStatus read_ring(const RingAttachment& ring, std::FILE* csv) {
  RingReader reader = ring.reader_from_oldest();
  TraceRecord record{};
  for (std::uint64_t rows = 0; rows <= ring.segment().layout().slot_count && reader.next(record); ++rows)
    hapfluid::rt::write_trace_row(csv, record, kMaxDevices);
  RingReader newest = ring.reader_from_newest();
  newest.read_at(newest.position() - 1, &record, sizeof record);
  newest.read_at(reader.position(), &record, sizeof record);
  const std::uint64_t now = monotonic_ns();
  ring.check_liveness(now, 1'000'000'000ull);
  return ring.status(now, 1'000'000'000ull);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const Object& object = Object::object();
  static std::vector<std::byte> buffer;
  if (size < 2) return 0;
  std::size_t first = data[0] | (std::size_t(data[1]) << 8);
  data += 2;
  size -= 2;
  if (first > size) first = size;
  const std::uint8_t* later = data + first;
  const std::size_t later_size = size - first;

  object.write(data, first);
  const HeaderFields at_attach = header_of(data, first);
  const auto kind = static_cast<ChannelKind>(at_attach.channel_kind);
  const bool known = kind == ChannelKind::device_states || kind == ChannelKind::sim_samples ||
                     kind == ChannelKind::particles || kind == ChannelKind::trace;
  try {
    // A reader expecting one channel and finding another (or none it knows) must refuse it.
    const ChannelKind expected = known ? kind : ChannelKind::sim_samples;
    if (expected == ChannelKind::trace) {
      RingAttachment ring = RingAttachment::attach(object.name, expected, payload_for(expected));
      ++hapfluid_fuzz_accepted;
      read_ring(ring, object.csv);
      if (later_size == 0) return 0;
      object.write(later, later_size);
      const bool corrupt = read_ring(ring, object.csv) == WriterStatus::corrupt;
      const bool changed = !(at_attach == header_of(later, later_size)) || pages(later_size) < pages(first);
      if (corrupt != changed)
        hapfluid_fuzz_violated(changed ? "a ring whose layout changed or that lost pages is not corrupt"
                                       : "a ring with its layout and pages intact reads as corrupt");
    } else {
      LatestReader reader = LatestReader::attach(object.name, expected, payload_for(expected));
      ++hapfluid_fuzz_accepted;
      read_latest(reader, buffer);
      if (later_size == 0) return 0;
      object.write(later, later_size);
      const bool corrupt = read_latest(reader, buffer) == WriterStatus::corrupt;
      const bool changed = !(at_attach == header_of(later, later_size)) || pages(later_size) < pages(first);
      if (corrupt != changed)
        hapfluid_fuzz_violated(changed ? "a segment whose layout changed or that lost pages is not corrupt"
                                       : "a segment with its layout and pages intact reads as corrupt");
    }
  } catch (const ShmError&) {
    // Refused at attach with the reason: the expected outcome for most inputs.
  }
  return 0;
}
