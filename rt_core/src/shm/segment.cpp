// Segment creation, attachment and validation: the only place that does shm syscalls.
#include <fcntl.h>
#include <grp.h>
#include <signal.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <new>
#include <utility>

#include "hapfluid/config/log.hpp"
#include "hapfluid/shm/channel.hpp"
#include "segment_trust.hpp"
#include "truncation_guard.hpp"

namespace hapfluid::shm {
namespace {

std::string errno_text(int err) { return std::string(std::strerror(err)); }

bool pid_alive(pid_t pid) {
  if (pid <= 0) return false;
  // EPERM: the process exists but belongs to someone else.
  return ::kill(pid, 0) == 0 || errno == EPERM;
}

std::uint64_t make_incarnation() {
  timespec ts{};
  ::clock_gettime(CLOCK_REALTIME, &ts);
  return (std::uint64_t(ts.tv_sec) * 1'000'000'000ull + std::uint64_t(ts.tv_nsec)) ^
         (std::uint64_t(::getpid()) << 40);
}

// Largest slot count a reader accepts: far above any channel's (at most the trace ring's
// records), low enough that slot_count * slot_bytes is checked without overflow.
constexpr std::uint64_t kMaxSlots = 1u << 24;

struct Layout {
  std::uint64_t slot_bytes;
  std::uint64_t total_bytes;
};

// The header's fields may be rewritten by another process at any time: relaxed atomic loads make
// reading them well defined whatever it does.
template <class T>
T load_shared(const T& field) {
  return std::atomic_ref<T>(const_cast<T&>(field)).load(std::memory_order_relaxed);
}

SegmentLayout read_layout(const SegmentHeader& h) {
  SegmentLayout l;
  l.channel_kind = load_shared(h.channel_kind);
  l.slot_count = load_shared(h.slot_count);
  l.slot_bytes = load_shared(h.slot_bytes);
  l.payload_bytes = load_shared(h.payload_bytes);
  l.total_bytes = load_shared(h.total_bytes);
  l.incarnation = load_shared(h.incarnation);
  l.writer_pid = load_shared(h.writer_pid);
  return l;
}

// Empty when the sizes describe slots that fit the object exactly, else what is wrong.
std::string layout_problem(const SegmentLayout& l, std::uint64_t object_bytes) {
  auto n = [](std::uint64_t v) { return std::to_string(v); };
  if (l.total_bytes != object_bytes)
    return "header says " + n(l.total_bytes) + " bytes but the object has " + n(object_bytes);
  if (l.slot_count == 0 || l.slot_count > kMaxSlots) return "slot_count " + n(l.slot_count) + " is out of range";
  if (l.slot_bytes < kSlotHeaderBytes || l.slot_bytes % kSlotHeaderBytes != 0 || l.slot_bytes > object_bytes)
    return "slot_bytes " + n(l.slot_bytes) + " is not a multiple of 64 that fits the object";
  // The unpadded size first: padding a size within 7 of 2^64 wraps it to a small one.
  if (l.payload_bytes > l.slot_bytes - kSlotHeaderBytes ||
      l.slot_bytes - kSlotHeaderBytes < padded_payload_bytes(l.payload_bytes))
    return "payload_bytes " + n(l.payload_bytes) + " does not fit a " + n(l.slot_bytes) + "-byte slot";
  // slot_bytes <= object_bytes and slot_count <= 2^24: the product cannot overflow.
  if (sizeof(SegmentHeader) + l.slot_bytes * l.slot_count != l.total_bytes)
    return n(l.slot_count) + " slots of " + n(l.slot_bytes) + " bytes do not add up to " + n(l.total_bytes);
  if (l.channel_kind == static_cast<std::uint32_t>(ChannelKind::trace) && (l.slot_count & (l.slot_count - 1)) != 0)
    return "trace ring of " + n(l.slot_count) + " records is not a power of two";
  return {};
}

Layout layout_for(std::uint32_t slot_count, std::uint64_t payload_bytes) {
  std::uint64_t slot_bytes = kSlotHeaderBytes + ((padded_payload_bytes(payload_bytes) + 63) / 64) * 64;
  return {slot_bytes, sizeof(SegmentHeader) + slot_bytes * slot_count};
}

void init_header(std::byte* base, ChannelKind kind, std::uint32_t slot_count, std::uint64_t payload_bytes,
                 const Layout& layout, pid_t pid) {
  // Fresh shm and anonymous mappings are zero-filled; only the header is (re)written here.
  std::memset(base, 0, sizeof(SegmentHeader));
  auto* h = new (base) SegmentHeader{};
  h->magic = kMagic;
  h->abi_version = kAbiVersion;
  h->channel_kind = static_cast<std::uint32_t>(kind);
  h->header_bytes = sizeof(SegmentHeader);
  h->slot_count = slot_count;
  h->slot_bytes = layout.slot_bytes;
  h->payload_bytes = payload_bytes;
  h->total_bytes = layout.total_bytes;
  h->writer_pid = pid;
  h->incarnation = make_incarnation();
  h->created_ns = monotonic_ns();
  for (std::uint32_t i = 0; i < slot_count; ++i)
    new (base + sizeof(SegmentHeader) + i * layout.slot_bytes) SlotHeader{};
  h->heartbeat_ns.store(h->created_ns, std::memory_order_relaxed);
  h->state.store(static_cast<std::uint32_t>(SegmentState::live), std::memory_order_release);
}

// A trusted segment under `name` (the name itself or one of its fallbacks) left by an earlier
// writer: removed, and said. Throws when a live writer owns it. Untrusted ones are left alone.
void remove_own_leftover(const std::string& name) {
  int fd = ::shm_open(name.c_str(), O_RDONLY, 0);
  if (fd < 0) return;  // nothing there (or unreadable: creating it will tell)
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !detail::trusted_owner(st.st_uid)) {
    ::close(fd);
    return;  // another user's: neither used nor removed (the writer takes a fallback name)
  }
  pid_t owner = 0;
  bool closed = false;
  if (st.st_size >= static_cast<off_t>(sizeof(SegmentHeader))) {
    void* p = ::mmap(nullptr, sizeof(SegmentHeader), PROT_READ, MAP_SHARED, fd, 0);
    if (p != MAP_FAILED) {
      // Its owner may shrink it while we look.
      int guard = detail::guard_mapping(static_cast<std::byte*>(p), sizeof(SegmentHeader), PROT_READ);
      const auto* h = static_cast<const SegmentHeader*>(p);
      if (load_shared(h->magic) == kMagic) {
        owner = load_shared(h->writer_pid);
        closed = h->state.load(std::memory_order_acquire) == static_cast<std::uint32_t>(SegmentState::closed);
      }
      if (detail::mapping_truncated(guard)) owner = 0;
      detail::unguard_mapping(guard);
      ::munmap(p, sizeof(SegmentHeader));
    }
  }
  ::close(fd);
  if (owner != 0 && owner != ::getpid() && !closed) {
    if (pid_alive(owner))
      throw ShmError("shm " + name + ": already written by running process pid " + std::to_string(owner) +
                     ": a channel has exactly one writer; stop that process or use another rt.shm.prefix");
    // Said once at start-up, so a crashed predecessor is never silent (its readers re-attach).
    log::notice("shm %s: replacing the segment left by pid %d, which is no longer running", name.c_str(),
                int(owner));
  }
  ::shm_unlink(name.c_str());
}

// Creates `name`, or a fallback name when an untrusted user holds it; returns the fd (or -1 with
// errno) and sets `created`.
int create_exclusive(const std::string& name, std::string& created) {
  created = name;
  int fd = ::shm_open(name.c_str(), O_RDWR | O_CREAT | O_EXCL, 0600);
  if (fd >= 0 || errno != EEXIST) return fd;
  std::string holder = "another user";
  if (int other = ::shm_open(name.c_str(), O_RDONLY, 0); other >= 0) {
    struct stat st {};
    bool trusted = ::fstat(other, &st) == 0 && detail::trusted_owner(st.st_uid);
    ::close(other);
    if (trusted) {  // a writer of ours created it since we looked: one writer per channel
      errno = EEXIST;
      return -1;
    }
    holder = detail::describe_user(st.st_uid);
  }
  for (int attempt = 0; attempt < 4 && fd < 0; ++attempt) {
    created = detail::new_fallback_name(name);
    fd = ::shm_open(created.c_str(), O_RDWR | O_CREAT | O_EXCL, 0600);
    if (fd < 0 && errno != EEXIST) return fd;
  }
  if (fd >= 0)
    log::warning("shm %s: the name is held by %s, which this writer neither trusts nor may remove: writing %s "
                 "instead (readers find it); remove the impostor with rm /dev/shm%s",
                 name.c_str(), holder.c_str(), created.c_str(), name.c_str());
  return fd;
}

}  // namespace

std::uint64_t monotonic_ns() {
  timespec ts{};
  ::clock_gettime(CLOCK_MONOTONIC, &ts);
  return std::uint64_t(ts.tv_sec) * 1'000'000'000ull + std::uint64_t(ts.tv_nsec);
}

std::uint64_t padded_payload_bytes(std::uint64_t payload_bytes) { return (payload_bytes + 7) / 8 * 8; }

const char* to_string(WriterStatus s) {
  switch (s) {
    case WriterStatus::not_attached: return "not attached";
    case WriterStatus::live: return "live";
    case WriterStatus::stale: return "stale (no heartbeat)";
    case WriterStatus::closed: return "closed by its writer";
    case WriterStatus::dead: return "writer process is gone";
    case WriterStatus::replaced: return "replaced by a restarted writer";
    case WriterStatus::corrupt: return "corrupt (its header changed or its object shrank since attach)";
  }
  return "?";
}

Segment::Segment(Segment&& o) noexcept { *this = std::move(o); }

Segment& Segment::operator=(Segment&& o) noexcept {
  if (this != &o) {
    release();
    name_ = std::move(o.name_);
    base_ = std::exchange(o.base_, nullptr);
    size_ = std::exchange(o.size_, 0);
    inode_ = std::exchange(o.inode_, 0);
    writable_ = std::exchange(o.writable_, false);
    layout_ = std::exchange(o.layout_, SegmentLayout{});
    truncation_guard_ = std::exchange(o.truncation_guard_, -1);
  }
  return *this;
}

Segment::~Segment() { release(); }

void Segment::release() {
  detail::unguard_mapping(std::exchange(truncation_guard_, -1));
  if (base_) ::munmap(base_, size_);
  base_ = nullptr;
  size_ = 0;
  layout_ = SegmentLayout{};
}

std::byte* Segment::slot(std::uint64_t index) const {
  return base_ + sizeof(SegmentHeader) + (index % layout_.slot_count) * layout_.slot_bytes;
}

bool Segment::intact() const {
  if (!base_) return false;
  // Touching the last word finds any shrink that could fault: truncation removes every page from
  // the new end on, so the last page goes first. On a shrunk object this load takes the guard's
  // SIGBUS path once and the flag below reads true from then on.
  if (truncation_guard_ >= 0)
    (void)std::atomic_ref<std::uint64_t>(*reinterpret_cast<std::uint64_t*>(base_ + size_ - 8))
        .load(std::memory_order_relaxed);
  if (detail::mapping_truncated(truncation_guard_)) return false;
  // A writer trusts its own header; a reader compares it with what it validated at attach.
  if (writable_) return true;
  const SegmentHeader& h = header();
  return load_shared(h.magic) == kMagic && load_shared(h.abi_version) == kAbiVersion &&
         load_shared(h.header_bytes) == sizeof(SegmentHeader) && read_layout(h) == layout_;
}

namespace {
// Guards a named mapping against its object being shrunk; throws if no guard is left.
int guard_or_throw(const std::string& name, void* p, std::size_t bytes, int prot) {
  int guard = detail::guard_mapping(static_cast<std::byte*>(p), bytes, prot);
  if (guard < 0) {
    ::munmap(p, bytes);
    throw ShmError("shm " + name + ": too many channel mappings in this process (or SIGBUS handler refused)");
  }
  return guard;
}
}  // namespace

Segment Segment::create(const std::string& name, ChannelKind kind, std::uint32_t slot_count,
                        std::uint64_t payload_bytes, const WriterOptions& options) {
  if (name.size() < 2 || name[0] != '/' || name.find('/', 1) != std::string::npos)
    throw ShmError("shm name \"" + name + "\": must be \"/<name>\" with no other '/'");
  if (slot_count == 0) throw ShmError("shm " + name + ": slot_count must be > 0");
  gid_t gid = static_cast<gid_t>(-1);
  if (!options.group.empty()) {
    struct group* g = ::getgrnam(options.group.c_str());
    if (!g)
      throw ShmError("shm " + name + ": group \"" + options.group +
                     "\" does not exist: create it (groupadd) or fix rt.shm.group in the rig file");
    gid = g->gr_gid;
  }
  if (options.mode & 0022) {
    char mode[16];
    std::snprintf(mode, sizeof mode, "%04o", options.mode);
    throw ShmError("shm " + name + ": mode " + mode +
                   " lets others than its writer write the channel, and readers refuse such a segment: use 0640");
  }
  remove_own_leftover(name);
  for (const std::string& fallback : detail::fallback_names(name)) remove_own_leftover(fallback);

  Layout layout = layout_for(slot_count, payload_bytes);
  // Created owner-only; fchmod below sets the exact mode (no process-wide umask games).
  std::string created;
  int fd = create_exclusive(name, created);
  int err = errno;
  if (fd < 0)
    throw ShmError("shm " + name + ": cannot create: " + errno_text(err) +
                   (err == EEXIST ? " (another writer created it at the same moment)" : ""));
  auto fail = [&](const std::string& what) {
    int e = errno;
    ::close(fd);
    ::shm_unlink(created.c_str());
    throw ShmError("shm " + created + ": " + what + ": " + errno_text(e));
  };
  if (gid != static_cast<gid_t>(-1) && ::fchown(fd, static_cast<uid_t>(-1), gid) != 0)
    fail("cannot give it to group \"" + options.group + "\" (the writer must be a member or root)");
  if (::fchmod(fd, options.mode) != 0) fail("cannot set mode");
  if (::ftruncate(fd, static_cast<off_t>(layout.total_bytes)) != 0)
    fail("cannot size it to " + std::to_string(layout.total_bytes) + " bytes (is /dev/shm full?)");
  void* p = ::mmap(nullptr, layout.total_bytes, PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
  if (p == MAP_FAILED) fail("cannot map it");
  struct stat st {};
  ::fstat(fd, &st);
  ::close(fd);

  Segment s;
  s.name_ = created;
  s.base_ = static_cast<std::byte*>(p);
  s.size_ = layout.total_bytes;
  s.inode_ = st.st_ino;
  s.writable_ = true;
  // A process that may write the object could also shrink it under us.
  s.truncation_guard_ = guard_or_throw(name, p, layout.total_bytes, PROT_READ | PROT_WRITE);
  init_header(s.base_, kind, slot_count, payload_bytes, layout, ::getpid());
  s.layout_ = read_layout(s.header());
  return s;
}

Segment Segment::create_private(ChannelKind kind, std::uint32_t slot_count, std::uint64_t payload_bytes) {
  Layout layout = layout_for(slot_count, payload_bytes);
  void* p = ::mmap(nullptr, layout.total_bytes, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  if (p == MAP_FAILED) throw ShmError("private ring: cannot map " + std::to_string(layout.total_bytes) + " bytes");
  Segment s;
  s.base_ = static_cast<std::byte*>(p);
  s.size_ = layout.total_bytes;
  s.writable_ = true;
  init_header(s.base_, kind, slot_count, payload_bytes, layout, ::getpid());
  s.layout_ = read_layout(s.header());
  return s;
}

namespace {
bool writer_running(const Segment& s) {
  return s.header().state.load(std::memory_order_acquire) == static_cast<std::uint32_t>(SegmentState::live) &&
         pid_alive(s.layout().writer_pid);
}
}  // namespace

Segment Segment::attach(const std::string& name, ChannelKind kind, std::uint64_t payload_bytes) {
  std::string refused;
  Segment s = attach_exact(name, kind, payload_bytes, refused);
  if (s.valid() && writer_running(s)) return s;
  // The name is missing, held by someone untrusted, or a leftover its new writer could not remove:
  // that writer then took a fallback name.
  for (const std::string& fallback : detail::fallback_names(name)) {
    std::string ignored;
    try {
      Segment candidate = attach_exact(fallback, kind, payload_bytes, ignored);
      if (candidate.valid() && writer_running(candidate)) return candidate;
    } catch (const ShmError&) {
      // A leftover or a half-created fallback: not the live writer.
    }
  }
  if (s.valid()) return s;  // a dead writer's segment: its readers see it as dead
  throw ShmError("shm " + name + ": " + refused);
}

Segment Segment::attach_exact(const std::string& name, ChannelKind kind, std::uint64_t payload_bytes,
                              std::string& refused) {
  int fd = ::shm_open(name.c_str(), O_RDONLY, 0);
  if (fd < 0) {
    int e = errno;
    refused = "cannot open: " + errno_text(e) +
              (e == ENOENT ? " (its writer has not started yet)"
               : e == EACCES ? " (add this user to the channel's group, rt.shm.group)"
                             : "");
    return {};
  }
  struct stat st {};
  if (::fstat(fd, &st) == 0) refused = detail::trust_problem(st);
  if (!refused.empty()) {
    ::close(fd);
    refused = "the segment " + refused + ": refusing it. Its writer has not started yet (it writes " + name +
              ".<hex> when the name is taken); remove the impostor with rm /dev/shm" + name;
    return {};
  }
  if (::fstat(fd, &st) != 0 || st.st_size < static_cast<off_t>(sizeof(SegmentHeader))) {
    ::close(fd);
    throw ShmError("shm " + name + ": too small to be a hapfluid segment (" + std::to_string(st.st_size) +
                   " bytes): its writer may still be creating it");
  }
  void* p = ::mmap(nullptr, static_cast<std::size_t>(st.st_size), PROT_READ, MAP_SHARED, fd, 0);
  ::close(fd);
  if (p == MAP_FAILED) throw ShmError("shm " + name + ": cannot map: " + errno_text(errno));
  Segment s;
  s.name_ = name;
  s.base_ = static_cast<std::byte*>(p);
  s.size_ = static_cast<std::size_t>(st.st_size);
  s.inode_ = st.st_ino;
  s.truncation_guard_ = guard_or_throw(name, p, s.size_, PROT_READ);
  // Every check below runs on one private copy; a writer changing the header afterwards makes
  // the segment corrupt (intact()), never moves what this reader touches.
  const SegmentHeader& h = s.header();
  const std::uint64_t magic = load_shared(h.magic);
  const std::uint32_t abi_version = load_shared(h.abi_version);
  const std::uint32_t header_bytes = load_shared(h.header_bytes);
  const SegmentLayout layout = read_layout(h);
  auto mismatch = [&](const std::string& what) { throw ShmError("shm " + name + ": " + what); };
  if (magic != kMagic) mismatch("not a hapfluid segment (bad magic)");
  if (h.state.load(std::memory_order_acquire) == static_cast<std::uint32_t>(SegmentState::initializing))
    mismatch("its writer is still initializing it; retry");
  if (abi_version != kAbiVersion)
    mismatch("ABI version " + std::to_string(abi_version) + " but this build expects " +
             std::to_string(kAbiVersion) + ": rebuild and restart every hapfluid process from one tree");
  if (layout.channel_kind != static_cast<std::uint32_t>(kind))
    mismatch(std::string("holds channel \"") + channel_name(static_cast<ChannelKind>(layout.channel_kind)) +
             "\" but \"" + channel_name(kind) + "\" was expected");
  if (header_bytes != sizeof(SegmentHeader)) mismatch("header size differs from this build's");
  if (payload_bytes != 0 && layout.payload_bytes != payload_bytes)
    mismatch("record size " + std::to_string(layout.payload_bytes) + " bytes but this build expects " +
             std::to_string(payload_bytes) + ": rebuild the processes from one tree");
  if (std::string problem = layout_problem(layout, s.size_); !problem.empty())
    mismatch("inconsistent sizes in its header (corrupt or foreign segment): " + problem);
  if (detail::mapping_truncated(s.truncation_guard_)) mismatch("its object shrank while it was being attached");
  s.layout_ = layout;
  return s;
}

void Segment::close() {
  if (!base_) return;
  if (writable_) {
    writable_header().state.store(static_cast<std::uint32_t>(SegmentState::closed), std::memory_order_release);
    if (!name_.empty()) {
      // Unlink only if the name still refers to our segment (a newer writer may own it now).
      int fd = ::shm_open(name_.c_str(), O_RDONLY, 0);
      if (fd >= 0) {
        struct stat st {};
        bool ours = ::fstat(fd, &st) == 0 && st.st_ino == inode_;
        ::close(fd);
        if (ours) ::shm_unlink(name_.c_str());
      }
    }
  }
  release();
}

WriterStatus header_status(const SegmentHeader& h, std::uint64_t now_ns, std::uint64_t stale_after_ns) {
  if (h.state.load(std::memory_order_acquire) == static_cast<std::uint32_t>(SegmentState::closed))
    return WriterStatus::closed;
  std::uint64_t beat = h.heartbeat_ns.load(std::memory_order_acquire);
  if (stale_after_ns != 0 && now_ns > beat && now_ns - beat > stale_after_ns) return WriterStatus::stale;
  return WriterStatus::live;
}

WriterStatus segment_liveness(const Segment& segment, std::uint64_t now_ns, std::uint64_t stale_after_ns) {
  if (!segment.valid()) return WriterStatus::not_attached;
  if (!segment.intact()) return WriterStatus::corrupt;
  int fd = ::shm_open(segment.name().c_str(), O_RDONLY, 0);
  if (fd >= 0) {
    struct stat st {};
    bool same = ::fstat(fd, &st) == 0 && st.st_ino == segment.inode();
    ::close(fd);
    if (!same) return WriterStatus::replaced;
  }
  WriterStatus s = header_status(segment.header(), now_ns, stale_after_ns);
  if (s == WriterStatus::closed) return s;
  if (!pid_alive(segment.layout().writer_pid)) return WriterStatus::dead;
  return s;
}

const char* channel_name(ChannelKind kind) {
  switch (kind) {
    case ChannelKind::device_states: return "device_states";
    case ChannelKind::sim_samples: return "sim_samples";
    case ChannelKind::particles: return "particles";
    case ChannelKind::trace: return "trace";
    case ChannelKind::flight_recorder: return "flight_recorder";
  }
  return "unknown";
}

std::string segment_name(const std::string& prefix, ChannelKind kind) {
  return "/" + prefix + "." + channel_name(kind);
}

}  // namespace hapfluid::shm
