// Lock-free shared-memory channels between the hapfluid processes (docs/architecture.md, Contracts).
//
// Ownership (iceoryx-style, explicit):
//   * One POSIX shm segment per channel, named "/<prefix>.<channel>", created by its single writer
//     with mode 0640 (group configurable): only the writer may write it, and only it maps it
//     writable; readers map it read-only and never write a byte, so any number can come and go.
//   * Readers trust a segment only if its owner is their own user or root and no one else may
//     write it; attach refuses any other, naming its owner. A writer whose name another user
//     holds takes a fallback name "<name>.<hex>" that readers look for (segment_trust.hpp), so a
//     squatter can neither hijack nor block a rig.
//   * The writer unlinks the segment on a clean close. A segment left behind by a crashed writer
//     is detected (its writer pid is gone) and replaced by the next writer.
//   * Every segment starts with a SegmentHeader: magic, ABI version, channel kind, sizes, writer
//     pid, an incarnation id, a heartbeat counter and timestamps. Readers check all of it at attach
//     and say clearly what does not match.
//   * Readers trust nothing in a segment after attach: they keep a private copy of its layout
//     (SegmentLayout) and index slots only with that copy, a header rewritten later or an object
//     shrunk later (a SIGBUS guard) makes the segment `corrupt`, which its users treat like a
//     dead writer. No content of a segment can crash a reader.
//
// Concurrency:
//   * LatestWriter/LatestReader ("latest value", e.g. device states, sim samples, particle frames):
//     an N-slot buffer; each slot carries a sequence word (odd while being written) and the
//     record's generation. The writer is wait-free (it never looks at readers). A reader loads the
//     published generation g, copies slot g % N and re-checks the sequence, and accepts the copy
//     only if the slot still holds generation g: a writer that lapped the ring in between may have
//     filled that slot with g + N before publishing it, and returning g + N then g + N - 1 would
//     run time backwards. A torn or lapped copy is retried a bounded number of times, so the read
//     is lock-free, monotonic and never returns a torn record.
//   * RingWriter/RingReader (trace): an overwrite ring of fixed records, each slot stamped with its
//     record index. The writer never blocks; a slow reader loses the oldest records and counts them.
//   * Payload bytes are copied as 8-byte relaxed atomics (std::atomic_ref), so concurrent access is
//     well defined; fences pair with the sequence words.
//
// Real-time use: create/attach/refresh/close/check_liveness do syscalls and belong outside the
// 1 kHz loop. publish/try_read/heartbeat/status are wait-free, allocation-free and syscall-free.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <sys/types.h>

#include "hapfluid/shm/layouts.hpp"

namespace hapfluid::shm {

inline constexpr std::uint64_t kMagic = 0x31464d4853504148ull;  // "HAPSHMF1" little-endian

enum class SegmentState : std::uint32_t { initializing = 0, live = 1, closed = 2 };

struct alignas(64) SegmentHeader {
  std::uint64_t magic;
  std::uint32_t abi_version;
  std::uint32_t channel_kind;    // ChannelKind
  std::uint32_t header_bytes;    // sizeof(SegmentHeader) of the writer's build
  std::uint32_t slot_count;
  std::uint64_t slot_bytes;      // bytes per slot, including its 64-byte slot header
  std::uint64_t payload_bytes;   // bytes of one record
  std::uint64_t total_bytes;
  std::int32_t writer_pid;
  std::uint32_t reserved0;
  std::uint64_t incarnation;     // unique per writer start: a changed value means "restarted writer"
  std::uint64_t created_ns;      // CLOCK_MONOTONIC at creation
  std::atomic<std::uint32_t> state;          // SegmentState; `live` is stored last at creation
  std::uint32_t reserved1;
  std::atomic<std::uint64_t> heartbeat;      // +1 per publish or explicit heartbeat()
  std::atomic<std::uint64_t> heartbeat_ns;   // CLOCK_MONOTONIC of the newest heartbeat
  std::atomic<std::uint64_t> published;      // records published so far (latest: generation)
};
static_assert(std::atomic<std::uint64_t>::is_always_lock_free, "cross-process atomics must be lock-free");
static_assert(sizeof(SegmentHeader) == 128);

// Monotonic clock in ns (vDSO, no syscall).
std::uint64_t monotonic_ns();

// A reader that runs as its own user (haptic-dashboard's observer) names the writers' user here,
// once, before it attaches: segments of that user are then trusted too, besides the process's
// own user and root. Nothing else changes: a segment others may write is still refused.
void trust_writer_uid(uid_t uid);

// What a reader concluded about its writer.
enum class WriterStatus {
  not_attached,  // no segment mapped (yet)
  live,          // heartbeat fresh
  stale,         // heartbeat older than the reader's stale limit
  closed,        // writer closed the channel cleanly
  dead,          // writer pid no longer exists (from check_liveness)
  replaced,      // the name now refers to a new segment: a restarted writer (from check_liveness)
  corrupt,       // the segment no longer has the layout it had at attach: treat the writer as dead
};
const char* to_string(WriterStatus);

struct WriterOptions {
  std::string group;        // owning group of the segment; empty: the process's group
  unsigned mode = 0640;      // no group or other write bit: readers refuse such a segment
};

// What a segment's header said at creation or attach, kept in process memory. Slots are found
// with this copy only, so a writer rewriting its header later cannot steer a reader out of bounds.
struct SegmentLayout {
  std::uint32_t channel_kind = 0;
  std::uint32_t slot_count = 0;
  std::uint64_t slot_bytes = 0;
  std::uint64_t payload_bytes = 0;
  std::uint64_t total_bytes = 0;
  std::uint64_t incarnation = 0;
  std::int32_t writer_pid = 0;
  bool operator==(const SegmentLayout&) const = default;
};

// A mapped segment: the RAII base of every writer and reader. Move-only.
class Segment {
 public:
  Segment() = default;
  Segment(Segment&&) noexcept;
  Segment& operator=(Segment&&) noexcept;
  Segment(const Segment&) = delete;
  Segment& operator=(const Segment&) = delete;
  ~Segment();

  // Writer side: creates "/name" holding `slot_count` slots of `payload_bytes` each. A segment
  // of the same name left by a dead writer (or one that closed) is replaced; one owned by a live
  // process is refused. Throws ShmError with the reason and the fix.
  static Segment create(const std::string& name, ChannelKind kind, std::uint32_t slot_count,
                        std::uint64_t payload_bytes, const WriterOptions& options = {});
  // Reader side: maps "/name" read-only and validates the header. `payload_bytes` 0 accepts the
  // writer's size (variable-size channels check it themselves). Throws ShmError naming what did
  // not match (missing segment, magic, ABI version, kind, size, still initializing, sizes that
  // do not add up to the object's size).
  static Segment attach(const std::string& name, ChannelKind kind, std::uint64_t payload_bytes);
  // Process-local anonymous mapping with the same layout (no name, never shared).
  static Segment create_private(ChannelKind kind, std::uint32_t slot_count, std::uint64_t payload_bytes);

  bool valid() const { return base_ != nullptr; }
  const std::string& name() const { return name_; }
  // The shared header: only its atomics (state, heartbeat, published) are meant to change; read
  // sizes and identity from layout().
  const SegmentHeader& header() const { return *reinterpret_cast<const SegmentHeader*>(base_); }
  SegmentHeader& writable_header() { return *reinterpret_cast<SegmentHeader*>(base_); }
  const SegmentLayout& layout() const { return layout_; }
  // Slot `index % slot_count` of the private layout: always inside the mapping.
  std::byte* slot(std::uint64_t index) const;
  bool writable() const { return writable_; }
  ino_t inode() const { return inode_; }
  // Wait-free, no syscall: the object was not shrunk and its header still matches layout().
  bool intact() const;

  // Writer: marks the segment closed, unmaps, and unlinks the name if it is still ours.
  void close();

 private:
  void release();
  // Maps exactly `name`. Missing or untrusted (owner, mode): an invalid Segment and the reason
  // in `refused`; any other mismatch throws.
  static Segment attach_exact(const std::string& name, ChannelKind kind, std::uint64_t payload_bytes,
                              std::string& refused);
  std::string name_;
  std::byte* base_ = nullptr;
  std::size_t size_ = 0;
  ino_t inode_ = 0;
  bool writable_ = false;
  SegmentLayout layout_;
  int truncation_guard_ = -1;
};

class ShmError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Slot layout: a 64-byte slot header (sequence, generation) followed by the payload.
struct alignas(64) SlotHeader {
  std::atomic<std::uint64_t> sequence;   // odd while the writer is inside the slot
  std::atomic<std::uint64_t> generation; // 1-based record number held by the slot
};
inline constexpr std::uint64_t kSlotHeaderBytes = 64;
std::uint64_t padded_payload_bytes(std::uint64_t payload_bytes);  // rounded up to 8 bytes

// ---------------------------------------------------------------------------------------------
// Latest-value channel.
enum class ReadResult {
  ok,           // `out` holds a consistent record newer than or equal to the previous read
  no_data,      // writer has not published yet
  busy,         // the writer overwrote the slot during every bounded attempt; try next tick
  overwritten,  // (read_generation) the slot no longer holds that generation: read the newest
  corrupt,      // the segment's header changed or its object shrank since attach: a dead writer
  not_attached,
};

class LatestWriter {
 public:
  LatestWriter() = default;
  static LatestWriter create(const std::string& name, ChannelKind kind, std::uint64_t payload_bytes,
                             std::uint32_t slot_count = 4, const WriterOptions& options = {});
  // Wait-free: copies `bytes` (<= payload_bytes) into the next slot and publishes it.
  std::uint64_t publish(const void* record, std::uint64_t bytes);
  template <class T> std::uint64_t publish(const T& record) { return publish(&record, sizeof(T)); }
  // Proves liveness without new data (e.g. a paused sim).
  void heartbeat();
  void close() { segment_.close(); }
  bool valid() const { return segment_.valid(); }
  const Segment& segment() const { return segment_; }

 private:
  Segment segment_;
};

class LatestReader {
 public:
  LatestReader() = default;
  explicit LatestReader(Segment segment) : segment_(std::move(segment)) {}
  static LatestReader attach(const std::string& name, ChannelKind kind, std::uint64_t payload_bytes) {
    return LatestReader(Segment::attach(name, kind, payload_bytes));
  }
  // Lock-free, bounded: at most `max_attempts` copies. `generation` receives the record number.
  ReadResult try_read(void* out, std::uint64_t bytes, std::uint64_t* generation = nullptr,
                      int max_attempts = 8) const;
  template <class T> ReadResult try_read(T& out, std::uint64_t* generation = nullptr) const {
    return try_read(&out, sizeof(T), generation);
  }
  // try_read's second step, after loading published(): copies record `generation` only if its
  // slot still holds exactly that record (ok), else `overwritten`. Public so that a test can
  // run a writer between the two steps.
  ReadResult read_generation(std::uint64_t generation, void* out, std::uint64_t bytes, int max_attempts = 1) const;
  // Heartbeat-based status; no syscall. stale_after_ns 0 disables the stale check.
  WriterStatus status(std::uint64_t now_ns, std::uint64_t stale_after_ns) const;
  // Non-RT: adds `dead` (pid gone) and `replaced` (a new segment under the name) to status().
  WriterStatus check_liveness(std::uint64_t now_ns, std::uint64_t stale_after_ns) const;
  std::uint64_t published() const;
  bool valid() const { return segment_.valid(); }
  const Segment& segment() const { return segment_; }

 private:
  Segment segment_;
};

// ---------------------------------------------------------------------------------------------
// Overwrite ring of fixed-size records (trace, flight recorder). The same code runs over a
// shared segment or over private memory (the flight recorder inside haptic-rt).
class RingWriter {
 public:
  RingWriter() = default;
  static RingWriter create(const std::string& name, ChannelKind kind, std::uint64_t record_bytes,
                           std::uint32_t record_count, const WriterOptions& options = {});
  // Private (process-local, anonymous) ring: no name, no syscalls after creation.
  static RingWriter create_private(ChannelKind kind, std::uint64_t record_bytes, std::uint32_t record_count);
  void push(const void* record, std::uint64_t bytes);
  template <class T> void push(const T& record) { push(&record, sizeof(T)); }
  std::uint64_t pushed() const;
  void close() { segment_.close(); }
  bool valid() const { return segment_.valid(); }
  const Segment& segment() const { return segment_; }

 private:
  Segment segment_;
};

class RingReader {
 public:
  RingReader() = default;
  explicit RingReader(const Segment& segment, std::uint64_t start_position)
      : segment_(&segment), position_(start_position) {}
  // Reads the next record; false when the reader has caught up. Records overwritten before they
  // could be read are skipped and added to lost().
  bool next(void* out, std::uint64_t bytes);
  template <class T> bool next(T& out) { return next(&out, sizeof(T)); }
  std::uint64_t position() const { return position_; }
  std::uint64_t lost() const { return lost_; }
  // Reads the record at an absolute index if it is still in the ring (flight recorder dumps).
  bool read_at(std::uint64_t index, void* out, std::uint64_t bytes) const;

 private:
  const Segment* segment_ = nullptr;
  std::uint64_t position_ = 0;
  std::uint64_t lost_ = 0;
};

// A reader-owned mapping of a ring channel in another process (haptic-trace).
class RingAttachment {
 public:
  static RingAttachment attach(const std::string& name, ChannelKind kind, std::uint64_t record_bytes) {
    RingAttachment a;
    a.segment_ = Segment::attach(name, kind, record_bytes);
    return a;
  }
  // Starts at the oldest record still in the ring.
  RingReader reader_from_oldest() const;
  RingReader reader_from_newest() const;
  const Segment& segment() const { return segment_; }
  WriterStatus status(std::uint64_t now_ns, std::uint64_t stale_after_ns) const;
  WriterStatus check_liveness(std::uint64_t now_ns, std::uint64_t stale_after_ns) const;

 private:
  Segment segment_;
};

// Shared by every reader type.
WriterStatus header_status(const SegmentHeader& header, std::uint64_t now_ns, std::uint64_t stale_after_ns);
WriterStatus segment_liveness(const Segment& segment, std::uint64_t now_ns, std::uint64_t stale_after_ns);

}  // namespace hapfluid::shm
