// The wait-free writers and lock-free readers of the latest-value and ring channels.
#include <atomic>
#include <cstring>

#include "hapfluid/shm/channel.hpp"

namespace hapfluid::shm {
namespace {

// Payload copies are 8-byte relaxed atomics: well-defined under concurrent access, and the
// sequence words with their fences order them.
void store_words(std::byte* dst, const void* src, std::uint64_t bytes) {
  const auto* s = static_cast<const unsigned char*>(src);
  auto* d = reinterpret_cast<std::uint64_t*>(dst);
  std::uint64_t words = bytes / 8;
  for (std::uint64_t i = 0; i < words; ++i) {
    std::uint64_t w;
    std::memcpy(&w, s + i * 8, 8);
    std::atomic_ref<std::uint64_t>(d[i]).store(w, std::memory_order_relaxed);
  }
  if (std::uint64_t tail = bytes % 8) {
    std::uint64_t w = 0;
    std::memcpy(&w, s + words * 8, tail);
    std::atomic_ref<std::uint64_t>(d[words]).store(w, std::memory_order_relaxed);
  }
}

void load_words(void* dst, const std::byte* src, std::uint64_t bytes) {
  auto* d = static_cast<unsigned char*>(dst);
  auto* s = const_cast<std::uint64_t*>(reinterpret_cast<const std::uint64_t*>(src));
  std::uint64_t words = bytes / 8;
  for (std::uint64_t i = 0; i < words; ++i) {
    std::uint64_t w = std::atomic_ref<std::uint64_t>(s[i]).load(std::memory_order_relaxed);
    std::memcpy(d + i * 8, &w, 8);
  }
  if (std::uint64_t tail = bytes % 8) {
    std::uint64_t w = std::atomic_ref<std::uint64_t>(s[words]).load(std::memory_order_relaxed);
    std::memcpy(d + words * 8, &w, tail);
  }
}

SlotHeader& slot_header(const Segment& s, std::uint64_t index) {
  return *reinterpret_cast<SlotHeader*>(s.slot(index));
}
std::byte* slot_payload(const Segment& s, std::uint64_t index) { return s.slot(index) + kSlotHeaderBytes; }

// The private layout bounds every copy, whatever the caller asked for.
std::uint64_t clamp_bytes(const Segment& s, std::uint64_t bytes) {
  return bytes > s.layout().payload_bytes ? s.layout().payload_bytes : bytes;
}

// Writes one record into slot `index` (reduced by Segment::slot) under its sequence word;
// `generation` is 1-based.
void write_slot(const Segment& s, std::uint64_t index, std::uint64_t generation, const void* record,
                std::uint64_t bytes) {
  SlotHeader& slot = slot_header(s, index);
  std::uint64_t seq = slot.sequence.load(std::memory_order_relaxed);
  slot.sequence.store(seq + 1, std::memory_order_relaxed);  // odd: writing
  std::atomic_thread_fence(std::memory_order_release);
  slot.generation.store(generation, std::memory_order_relaxed);
  store_words(slot_payload(s, index), record, bytes);
  slot.sequence.store(seq + 2, std::memory_order_release);  // even: complete
}

// One attempt at a consistent copy of slot `index`; false when the writer interfered.
bool read_slot(const Segment& s, std::uint64_t index, void* out, std::uint64_t bytes, std::uint64_t* generation) {
  const SlotHeader& slot = slot_header(s, index);
  std::uint64_t before = slot.sequence.load(std::memory_order_acquire);
  if (before & 1) return false;
  std::uint64_t gen = slot.generation.load(std::memory_order_relaxed);
  load_words(out, slot_payload(s, index), bytes);
  std::atomic_thread_fence(std::memory_order_acquire);
  if (slot.sequence.load(std::memory_order_relaxed) != before) return false;
  if (generation) *generation = gen;
  return true;
}

void beat(SegmentHeader& h) {
  h.heartbeat.fetch_add(1, std::memory_order_relaxed);
  h.heartbeat_ns.store(monotonic_ns(), std::memory_order_release);
}

}  // namespace

// ---- latest value ---------------------------------------------------------------------------
LatestWriter LatestWriter::create(const std::string& name, ChannelKind kind, std::uint64_t payload_bytes,
                                  std::uint32_t slot_count, const WriterOptions& options) {
  LatestWriter w;
  w.segment_ = Segment::create(name, kind, slot_count < 2 ? 2 : slot_count, payload_bytes, options);
  return w;
}

std::uint64_t LatestWriter::publish(const void* record, std::uint64_t bytes) {
  SegmentHeader& h = segment_.writable_header();
  bytes = clamp_bytes(segment_, bytes);
  std::uint64_t generation = h.published.load(std::memory_order_relaxed) + 1;
  write_slot(segment_, generation, generation, record, bytes);
  h.published.store(generation, std::memory_order_release);
  beat(h);
  return generation;
}

void LatestWriter::heartbeat() { beat(segment_.writable_header()); }

ReadResult LatestReader::read_generation(std::uint64_t generation, void* out, std::uint64_t bytes,
                                         int max_attempts) const {
  if (!segment_.valid()) return ReadResult::not_attached;
  if (generation == 0) return ReadResult::no_data;
  bytes = clamp_bytes(segment_, bytes);
  ReadResult result = ReadResult::busy;
  for (int attempt = 0; attempt < max_attempts && result == ReadResult::busy; ++attempt) {
    std::uint64_t held = 0;
    if (read_slot(segment_, generation, out, bytes, &held))
      result = held == generation ? ReadResult::ok : ReadResult::overwritten;
  }
  // Checked after the copy: a shrunk object reads as zero pages, a rewritten header as anything.
  return segment_.intact() ? result : ReadResult::corrupt;
}

ReadResult LatestReader::try_read(void* out, std::uint64_t bytes, std::uint64_t* generation,
                                  int max_attempts) const {
  if (!segment_.valid()) return ReadResult::not_attached;
  for (int attempt = 0; attempt < max_attempts; ++attempt) {
    std::uint64_t newest = published();
    ReadResult r = read_generation(newest, out, bytes);
    if (r == ReadResult::ok && generation) *generation = newest;
    // busy (torn) and overwritten (lapped): the writer moved on; look at the newest again.
    if (r != ReadResult::busy && r != ReadResult::overwritten) return r;
  }
  return ReadResult::busy;
}

WriterStatus LatestReader::status(std::uint64_t now_ns, std::uint64_t stale_after_ns) const {
  if (!segment_.valid()) return WriterStatus::not_attached;
  if (!segment_.intact()) return WriterStatus::corrupt;
  return header_status(segment_.header(), now_ns, stale_after_ns);
}
WriterStatus LatestReader::check_liveness(std::uint64_t now_ns, std::uint64_t stale_after_ns) const {
  return segment_liveness(segment_, now_ns, stale_after_ns);
}

std::uint64_t LatestReader::published() const {
  return segment_.valid() ? segment_.header().published.load(std::memory_order_acquire) : 0;
}

// ---- ring -------------------------------------------------------------------------------------
RingWriter RingWriter::create(const std::string& name, ChannelKind kind, std::uint64_t record_bytes,
                              std::uint32_t record_count, const WriterOptions& options) {
  if (record_count == 0 || (record_count & (record_count - 1)) != 0)
    throw ShmError("ring " + name + ": record_count " + std::to_string(record_count) + " must be a power of two");
  RingWriter w;
  w.segment_ = Segment::create(name, kind, record_count, record_bytes, options);
  return w;
}

RingWriter RingWriter::create_private(ChannelKind kind, std::uint64_t record_bytes, std::uint32_t record_count) {
  if (record_count == 0 || (record_count & (record_count - 1)) != 0)
    throw ShmError("private ring: record_count " + std::to_string(record_count) + " must be a power of two");
  RingWriter w;
  w.segment_ = Segment::create_private(kind, record_count, record_bytes);
  return w;
}

void RingWriter::push(const void* record, std::uint64_t bytes) {
  SegmentHeader& h = segment_.writable_header();
  bytes = clamp_bytes(segment_, bytes);
  std::uint64_t index = h.published.load(std::memory_order_relaxed);  // 0-based record index
  write_slot(segment_, index, index + 1, record, bytes);
  h.published.store(index + 1, std::memory_order_release);
  beat(h);
}

std::uint64_t RingWriter::pushed() const { return segment_.header().published.load(std::memory_order_relaxed); }

bool RingReader::read_at(std::uint64_t index, void* out, std::uint64_t bytes) const {
  bytes = clamp_bytes(*segment_, bytes);
  std::uint64_t generation = 0;
  for (int attempt = 0; attempt < 4; ++attempt) {
    if (read_slot(*segment_, index, out, bytes, &generation))
      return generation == index + 1 && segment_->intact();
  }
  return false;
}

bool RingReader::next(void* out, std::uint64_t bytes) {
  if (!segment_ || !segment_->valid() || !segment_->intact()) return false;
  const SegmentHeader& h = segment_->header();
  const std::uint64_t slot_count = segment_->layout().slot_count;
  for (int attempt = 0; attempt < 64; ++attempt) {  // bounded even against a corrupt segment
    std::uint64_t written = h.published.load(std::memory_order_acquire);
    if (position_ >= written) return false;
    if (written - position_ > slot_count) {  // lapped: the oldest records are gone
      lost_ += written - slot_count - position_;
      position_ = written - slot_count;
    }
    if (read_at(position_, out, bytes)) {
      ++position_;
      return true;
    }
    // Overwritten while we copied it (or still being written by a lapping writer): skip it.
    std::uint64_t now_written = h.published.load(std::memory_order_acquire);
    if (now_written - position_ > slot_count - 1) {
      ++lost_;
      ++position_;
    }
  }
  return false;
}

RingReader RingAttachment::reader_from_oldest() const {
  std::uint64_t written = segment_.header().published.load(std::memory_order_acquire);
  std::uint64_t n = segment_.layout().slot_count;
  return RingReader(segment_, written > n ? written - n : 0);
}

RingReader RingAttachment::reader_from_newest() const {
  return RingReader(segment_, segment_.header().published.load(std::memory_order_acquire));
}

WriterStatus RingAttachment::status(std::uint64_t now_ns, std::uint64_t stale_after_ns) const {
  if (!segment_.valid()) return WriterStatus::not_attached;
  if (!segment_.intact()) return WriterStatus::corrupt;
  return header_status(segment_.header(), now_ns, stale_after_ns);
}

WriterStatus RingAttachment::check_liveness(std::uint64_t now_ns, std::uint64_t stale_after_ns) const {
  return segment_liveness(segment_, now_ns, stale_after_ns);
}

}  // namespace hapfluid::shm
