// The hand-off between the 1 kHz loop and a transport's own I/O thread, for transports whose
// device I/O may block or lock: a hidraw write waits for its USB transfer (5-14 ms on a rig);
// libusb's submit and event handling take libusb's mutexes and make system calls. Their I/O runs
// on threads of their own, and the loop's side of the transport only copies frames into and out
// of fixed rings and reads a few atomics: no lock, no system call, no allocation, no wait.
//
// One ring per direction, one producer and one consumer each. The producer never waits: when
// the consumer has fallen a whole ring behind, the oldest unread frame is overwritten, and a
// consumer that was lapped resumes at the newest frame. A device that keeps up gets every frame
// in order; one that stalls (a slow USB device) gets the newest command, not a backlog of stale
// ones, and a loop that stalled gets the newest state. Slots are sequence-stamped like the shared-
// memory channels' (rt_core/src/shm/channels.cpp), so a frame is never read half overwritten.
// Unit-tested in tests/firmware_bridge/test_frame_handoff.cpp.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "hapfluid/device/transport.hpp"

namespace hapfluid::device {

// Frames towards the device: one tick sends at most a command, an e-stop and a heartbeat; more
// queued than that would only be older commands.
inline constexpr std::size_t kSendRingFrames = 4;
// Frames from the device: 64 ms of states at 1 kHz, so a loop that stalled loses nothing newer.
inline constexpr std::size_t kReceiveRingFrames = 64;
// How long an I/O thread with nothing to send sleeps before it looks again: the most a command
// waits in the ring before its thread takes it (the loop wakes no one, that would be a syscall).
inline constexpr long kSendPickupNs = 250'000;

template <std::size_t N>
class FrameRing {
 public:
  // Producer: never waits, never fails.
  void push(const WireFrame& frame) noexcept {
    const std::uint64_t index = head_.load(std::memory_order_relaxed);
    Slot& slot = slots_[index % N];
    slot.stamp.store(2 * index + 1, std::memory_order_relaxed);  // odd: being written
    std::atomic_thread_fence(std::memory_order_release);
    std::uint64_t words[kWords] = {};
    std::memcpy(words, &frame, sizeof frame);
    for (std::size_t i = 0; i < kWords; ++i) slot.words[i].store(words[i], std::memory_order_relaxed);
    slot.stamp.store(2 * index + 2, std::memory_order_release);  // even: frame `index` complete
    head_.store(index + 1, std::memory_order_release);
  }

  // Consumer: the next frame in order, or the newest once the producer lapped this consumer (the
  // frames in between are counted in dropped()); false when nothing new is there. At most a few
  // attempts: a retry happens only when the producer lapped the consumer during its copy.
  bool pop(WireFrame& out) noexcept {
    for (int attempt = 0; attempt < 4; ++attempt) {
      const std::uint64_t head = head_.load(std::memory_order_acquire);
      if (next_ == head) return false;
      if (head - next_ > N) skip_to(head - 1);
      const Slot& slot = slots_[next_ % N];
      const std::uint64_t complete = 2 * next_ + 2;
      if (slot.stamp.load(std::memory_order_acquire) != complete) continue;  // overwritten meanwhile
      std::uint64_t words[kWords];
      for (std::size_t i = 0; i < kWords; ++i) words[i] = slot.words[i].load(std::memory_order_relaxed);
      std::atomic_thread_fence(std::memory_order_acquire);
      if (slot.stamp.load(std::memory_order_relaxed) != complete) continue;
      std::memcpy(&out, words, sizeof out);
      ++next_;
      return true;
    }
    return false;
  }

  // Consumer: forgets every frame not taken yet (counted as dropped), e.g. commands queued for a
  // connection that was lost, which must not reach the next one.
  void discard() noexcept { skip_to(head_.load(std::memory_order_acquire)); }

  // Frames the consumer never took; any thread may read it.
  std::uint64_t dropped() const noexcept { return dropped_.load(std::memory_order_relaxed); }

 private:
  static constexpr std::size_t kWords = (sizeof(WireFrame) + 7) / 8;
  struct Slot {
    std::atomic<std::uint64_t> stamp{0};  // 2i+1 while frame i is written, 2i+2 once it is complete
    std::atomic<std::uint64_t> words[kWords] = {};
  };

  void skip_to(std::uint64_t index) noexcept {
    dropped_.store(dropped_.load(std::memory_order_relaxed) + (index - next_), std::memory_order_relaxed);
    next_ = index;
  }

  Slot slots_[N];
  alignas(64) std::atomic<std::uint64_t> head_{0};  // frames pushed so far (the producer's)
  alignas(64) std::uint64_t next_ = 0;              // the next frame to take (the consumer's)
  std::atomic<std::uint64_t> dropped_{0};           // written by the consumer only
};

// The loop's half of a transport whose device I/O runs on its own thread(s), the same for every
// such transport (hidapi, libusb): send queues a frame for the I/O thread, receive takes one it
// received, the error bits and the reconnection count are atomics the I/O thread keeps current.
// The derived class's I/O threads use the protected calls; nothing else touches the rings.
class HandoffTransport : public Transport {
 public:
  // Io::error while the device is disconnected (the frame is not queued: it would be stale by the
  // time a device is there again).
  Io send(const WireFrame& frame) final {
    if (errors_.load(std::memory_order_relaxed) & kDisconnected) return Io::error;
    to_device_.push(frame);
    return Io::ok;
  }
  Io receive(WireFrame& frame) final {
    const std::uint64_t dropped = from_device_.dropped();
    if (from_device_.pop(frame)) {
      if (from_device_.dropped() != dropped) raise(kRxOverflow);  // the loop stalled a whole ring long
      return Io::ok;
    }
    return (errors_.load(std::memory_order_relaxed) & kDisconnected) ? Io::error : Io::empty;
  }
  int poll_fd() const final { return -1; }
  std::uint32_t error_flags() const final { return errors_.load(std::memory_order_relaxed); }
  // kDisconnected describes the link now, not an event: it stays until the device is back.
  void clear_error_flags() final { errors_.fetch_and(kDisconnected, std::memory_order_relaxed); }
  std::uint32_t reconnects() const final { return reconnects_.load(std::memory_order_acquire); }

 protected:
  // I/O thread: the next frame to send; frames a slow device had no time for are skipped (newest
  // wins) and reported as kTxFailed.
  bool next_to_send(WireFrame& frame) {
    const std::uint64_t dropped = to_device_.dropped();
    if (!to_device_.pop(frame)) return false;
    if (to_device_.dropped() != dropped) raise(kTxFailed);
    return true;
  }
  void discard_unsent() { to_device_.discard(); }
  void received(const WireFrame& frame) { from_device_.push(frame); }
  void raise(std::uint32_t bits) { errors_.fetch_or(bits, std::memory_order_relaxed); }
  void lower(std::uint32_t bits) { errors_.fetch_and(~bits, std::memory_order_relaxed); }
  // A lost link is back (HapticArm restarts its sequence tracking): counted before the new
  // connection's first frame is queued.
  void reconnected() { reconnects_.fetch_add(1, std::memory_order_release); }

 private:
  FrameRing<kSendRingFrames> to_device_;        // loop -> I/O thread
  FrameRing<kReceiveRingFrames> from_device_;   // I/O thread -> loop
  std::atomic<std::uint32_t> errors_{0};
  std::atomic<std::uint32_t> reconnects_{0};
};

}  // namespace hapfluid::device
