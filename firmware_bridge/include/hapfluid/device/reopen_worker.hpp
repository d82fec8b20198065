// Reopening a lost device without blocking the thread that uses it. Opening (libusb_init +
// enumeration, hid_open, a CAN socket's bind) allocates and blocks for milliseconds, so a
// transport whose device vanished, or was absent at open, hands the dead handle (or none) to this
// worker's thread, which closes it and calls `open` every `period_ms` until it returns a handle;
// the handle's user picks that up with take(): the 1 kHz loop itself for SocketCAN, the
// transport's I/O thread for libusb and hidapi. Both directions are one atomic exchange, and
// waking the idle thread is one futex call: no lock, no allocation, no wait for the user.
// Unit-tested with a fake handle (tests/firmware_bridge/test_reopen_worker.cpp).
#pragma once

#include <pthread.h>
#include <time.h>

#include <atomic>
#include <functional>
#include <string>
#include <thread>

#include "hapfluid/device/open_failure.hpp"

namespace hapfluid::device {

template <class Handle>
class ReopenWorker {
 public:
  // open: a new handle, or nullptr with the attempt saying why (absent, or there but refusing:
  // both are retried, a persisting refusal is logged once under `name`); never called from the
  // handle's user. close: releases a handle given back by retire() or never taken.
  ReopenWorker(std::string name, std::function<Handle*(OpenAttempt&)> open, std::function<void(Handle*)> close,
               int period_ms = 200)
      : name_(std::move(name)), open_(std::move(open)), close_(std::move(close)), period_ms_(period_ms),
        thread_([this] {
          pthread_setname_np(pthread_self(), "hapfluid-reopen");
          run();
        }) {}

  ReopenWorker(const ReopenWorker&) = delete;
  ReopenWorker& operator=(const ReopenWorker&) = delete;

  // Stops the thread (an open in progress finishes first) and closes what is left.
  ~ReopenWorker() {
    command_.store(kStop);
    command_.notify_one();
    thread_.join();
    close_if(retired_.exchange(nullptr));
    close_if(fresh_.exchange(nullptr));
  }

  // The user: `dead` (may be null) is closed by the worker, which then reopens until it succeeds.
  void retire(Handle* dead) {
    retired_.store(dead);
    int idle = kIdle;
    if (command_.compare_exchange_strong(idle, kReopen)) command_.notify_one();
  }

  // The transport's constructor: one open on the calling thread. A device absent at open starts
  // the search (nullptr back: the caller reports kDisconnected and adopts take() later); a
  // permanent failure comes back in `attempt` for the caller to throw.
  Handle* first_open(OpenAttempt& attempt) {
    Handle* h = open_(attempt);
    if (!h && attempt.failure == OpenFailure::absent) retire(nullptr);
    return h;
  }

  // The user: the reopened handle, once (then the worker idles until the next retire()).
  Handle* take() { return fresh_.exchange(nullptr); }

  // Whether the worker is still trying (for reports; not needed to use it).
  bool reopening() const { return command_.load() == kReopen; }

 private:
  enum : int { kIdle, kReopen, kStop };

  void close_if(Handle* h) {
    if (h) close_(h);
  }

  void run() {
    for (;;) {
      const int command = command_.load();
      if (command == kStop) return;
      if (command == kIdle) {
        command_.wait(kIdle);
        continue;
      }
      close_if(retired_.exchange(nullptr));
      OpenAttempt attempt;
      if (Handle* h = open_(attempt)) {
        refusals_.clear();
        fresh_.store(h);
        int reopen = kReopen;
        command_.compare_exchange_strong(reopen, kIdle);  // a kStop meanwhile stays
        continue;
      }
      refusals_.note(name_, attempt);
      for (int ms = 0; ms < period_ms_ && command_.load() == kReopen; ms += 10) {
        timespec nap{0, 10'000'000};
        nanosleep(&nap, nullptr);
      }
    }
  }

  const std::string name_;
  RefusalLog refusals_;  // the worker thread's only
  std::function<Handle*(OpenAttempt&)> open_;
  std::function<void(Handle*)> close_;
  const int period_ms_;
  std::atomic<Handle*> retired_{nullptr};
  std::atomic<Handle*> fresh_{nullptr};
  std::atomic<int> command_{kIdle};
  std::thread thread_;  // last: started once everything above exists
};

}  // namespace hapfluid::device
