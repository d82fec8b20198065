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

#include "hapfluid/shm/channel.hpp"

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

struct Layout {
  std::uint64_t slot_bytes;
  std::uint64_t total_bytes;
};

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

// An existing segment under `name`: may we replace it? Throws when a live writer owns it.
void check_existing_owner(const std::string& name) {
  int fd = ::shm_open(name.c_str(), O_RDONLY, 0);
  if (fd < 0) return;  // nothing there (or unreadable: shm_unlink below will tell)
  struct stat st {};
  pid_t owner = 0;
  bool closed = false;
  if (::fstat(fd, &st) == 0 && st.st_size >= static_cast<off_t>(sizeof(SegmentHeader))) {
    void* p = ::mmap(nullptr, sizeof(SegmentHeader), PROT_READ, MAP_SHARED, fd, 0);
    if (p != MAP_FAILED) {
      const auto* h = static_cast<const SegmentHeader*>(p);
      if (h->magic == kMagic) {
        owner = h->writer_pid;
        closed = h->state.load(std::memory_order_acquire) == static_cast<std::uint32_t>(SegmentState::closed);
      }
      ::munmap(p, sizeof(SegmentHeader));
    }
  }
  ::close(fd);
  if (owner == 0 || owner == ::getpid() || closed) return;
  if (pid_alive(owner))
    throw ShmError("shm " + name + ": already written by running process pid " + std::to_string(owner) +
                   ": a channel has exactly one writer; stop that process or use another rt.shm.prefix");
  // Said once at start-up, so a crashed predecessor is never silent (its readers re-attach).
  std::fprintf(stderr, "shm %s: replacing the segment left by pid %d, which is no longer running\n", name.c_str(),
               int(owner));
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
  }
  return *this;
}

Segment::~Segment() { release(); }

void Segment::release() {
  if (base_) ::munmap(base_, size_);
  base_ = nullptr;
  size_ = 0;
}

std::byte* Segment::slot(std::uint64_t index) const {
  const auto& h = header();
  return base_ + sizeof(SegmentHeader) + index * h.slot_bytes;
}

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
  check_existing_owner(name);
  ::shm_unlink(name.c_str());  // a dead writer's leftover; ENOENT is the normal case

  Layout layout = layout_for(slot_count, payload_bytes);
  // Created owner-only; fchmod below sets the exact mode (no process-wide umask games).
  int fd = ::shm_open(name.c_str(), O_RDWR | O_CREAT | O_EXCL, 0600);
  int err = errno;
  if (fd < 0)
    throw ShmError("shm " + name + ": cannot create: " + errno_text(err) +
                   (err == EEXIST ? " (another writer created it at the same moment)" : ""));
  auto fail = [&](const std::string& what) {
    int e = errno;
    ::close(fd);
    ::shm_unlink(name.c_str());
    throw ShmError("shm " + name + ": " + what + ": " + errno_text(e));
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
  s.name_ = name;
  s.base_ = static_cast<std::byte*>(p);
  s.size_ = layout.total_bytes;
  s.inode_ = st.st_ino;
  s.writable_ = true;
  init_header(s.base_, kind, slot_count, payload_bytes, layout, ::getpid());
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
  return s;
}

Segment Segment::attach(const std::string& name, ChannelKind kind, std::uint64_t payload_bytes) {
  int fd = ::shm_open(name.c_str(), O_RDONLY, 0);
  if (fd < 0) {
    int e = errno;
    throw ShmError("shm " + name + ": cannot open: " + errno_text(e) +
                   (e == ENOENT ? " (its writer has not started yet)"
                    : e == EACCES ? " (add this user to the channel's group, rt.shm.group)"
                                  : ""));
  }
  struct stat st {};
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
  const SegmentHeader& h = s.header();
  auto mismatch = [&](const std::string& what) { throw ShmError("shm " + name + ": " + what); };
  if (h.magic != kMagic) mismatch("not a hapfluid segment (bad magic)");
  if (h.state.load(std::memory_order_acquire) == static_cast<std::uint32_t>(SegmentState::initializing))
    mismatch("its writer is still initializing it; retry");
  if (h.abi_version != kAbiVersion)
    mismatch("ABI version " + std::to_string(h.abi_version) + " but this build expects " +
             std::to_string(kAbiVersion) + ": rebuild and restart every hapfluid process from one tree");
  if (h.channel_kind != static_cast<std::uint32_t>(kind))
    mismatch(std::string("holds channel \"") + channel_name(static_cast<ChannelKind>(h.channel_kind)) +
             "\" but \"" + channel_name(kind) + "\" was expected");
  if (h.header_bytes != sizeof(SegmentHeader)) mismatch("header size differs from this build's");
  if (payload_bytes != 0 && h.payload_bytes != payload_bytes)
    mismatch("record size " + std::to_string(h.payload_bytes) + " bytes but this build expects " +
             std::to_string(payload_bytes) + ": rebuild the processes from one tree");
  if (h.total_bytes != s.size_ || h.slot_count == 0 ||
      h.total_bytes != sizeof(SegmentHeader) + h.slot_bytes * h.slot_count ||
      h.slot_bytes < kSlotHeaderBytes + padded_payload_bytes(h.payload_bytes))
    mismatch("inconsistent sizes in its header (corrupt or foreign segment)");
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
  int fd = ::shm_open(segment.name().c_str(), O_RDONLY, 0);
  if (fd >= 0) {
    struct stat st {};
    bool same = ::fstat(fd, &st) == 0 && st.st_ino == segment.inode();
    ::close(fd);
    if (!same) return WriterStatus::replaced;
  }
  WriterStatus s = header_status(segment.header(), now_ns, stale_after_ns);
  if (s == WriterStatus::closed) return s;
  if (!pid_alive(segment.header().writer_pid)) return WriterStatus::dead;
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
