// Counters of what the real-time rules forbid in the 1 kHz loop, on the threads that ask to be
// watched: heap allocations (malloc, calloc, realloc, operator new), lock calls (pthread mutex
// and rwlock locks) and system calls. The first two replace the C library's functions in any
// executable that links this (so calls from shared libraries such as hidapi and libusb count
// too); system calls are caught by a seccomp filter on the watched thread, which hands each one
// to a supervisor thread that counts it and lets it run (SECCOMP_RET_USER_NOTIF with
// SECCOMP_USER_NOTIF_FLAG_CONTINUE), so nothing escapes: not the C library's internal calls, not a
// contended lock's futex, not a raw syscall(). The loop's own clock reads and its sleep are let
// through uncounted: they are how a loop keeps its period, not device I/O; so are the calls a
// caller names as allowed (a socket transport's non-blocking reads and writes), in the kernel,
// without the round trip to the supervisor that would slow the thread down.
#pragma once

#include <atomic>
#include <cstdint>
#include <string>
#include <thread>
#include <vector>

namespace hapfluid::counters {

// Allocations and lock calls are counted on the calling thread while this is on.
void count_on_this_thread(bool on);
long allocations();
long locks();
void reset_counts();

class SyscallWatch {
 public:
  SyscallWatch();
  ~SyscallWatch();
  SyscallWatch(const SyscallWatch&) = delete;
  SyscallWatch& operator=(const SyscallWatch&) = delete;

  // On the thread to watch; permanent for that thread (run the loop on a thread that ends
  // after). `allowed`: system call names let through uncounted besides the clock (e.g. "read").
  // False with `why` when a name is unknown or the kernel refuses the filter.
  bool watch_this_thread(std::string& why, const std::vector<std::string>& allowed = {});
  // The counting window, opened and closed by the watched thread itself.
  void start() { counting_.store(true); }
  void stop() { counting_.store(false); }
  long total() const;
  // "write 12, ioctl 3" (empty when none).
  std::string summary() const;

 private:
  static constexpr int kSyscalls = 512;
  void supervise();
  std::atomic<int> listener_{-1};
  std::atomic<bool> counting_{false}, stop_{false};
  std::atomic<long> counts_[kSyscalls] = {};
  std::thread supervisor_;  // started before any filter exists: its own calls are never caught
};

}  // namespace hapfluid::counters
