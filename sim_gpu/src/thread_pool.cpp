#include "hapfluid/sim/thread_pool.hpp"

#include <sched.h>

#include <algorithm>
#include <chrono>
#include <stdexcept>

namespace hapfluid::sim {
namespace {

inline void cpu_relax() {
#if defined(__x86_64__) || defined(__i386__)
  __builtin_ia32_pause();
#elif defined(__aarch64__)
  asm volatile("yield");
#endif
}

// Spins until done() holds or `ns` have passed; true if done() held.
template <class Done>
bool spin_until(Done&& done, long ns) {
  if (done()) return true;  // the common hand-off: no clock read
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::nanoseconds(ns);
  for (;;) {
    for (int k = 0; k < 64; ++k) {
      if (done()) return true;
      cpu_relax();
    }
    if (std::chrono::steady_clock::now() >= deadline) return done();
  }
}

}  // namespace

int usable_cpus() {
  cpu_set_t set;
  if (sched_getaffinity(0, sizeof set, &set) != 0) return 1;
  const int n = CPU_COUNT(&set);
  return n > 0 ? std::min(n, kMaxWorkerThreads) : 1;
}

ThreadPool::ThreadPool(int threads) : threads_(threads), slots_(threads > kSlots ? threads : kSlots) {
  if (threads < 1) throw std::invalid_argument("thread count must be >= 1");
  active_.store(threads, std::memory_order_relaxed);
  for (int w = 1; w < threads; ++w) helpers_.emplace_back([this, w] { worker_loop(w); });
}

ThreadPool::~ThreadPool() {
  {
    std::lock_guard lock(mutex_);
    stopping_.store(true);
  }
  start_cv_.notify_all();
  for (auto& t : helpers_) t.join();
}

namespace {
constexpr std::uint64_t kSlotMask = 0xffffffffu;
std::uint64_t tag(unsigned long generation) { return (static_cast<std::uint64_t>(generation) & kSlotMask) << 32; }
}  // namespace

void ThreadPool::take_slots(unsigned long generation, bool caller) {
  const std::uint64_t mine = tag(generation);
  for (;;) {
    std::uint64_t v = next_.load(std::memory_order_acquire);
    do {
      if ((v & ~kSlotMask) != mine || static_cast<int>(v & kSlotMask) >= slots_) return;
    } while (!next_.compare_exchange_weak(v, v + 1, std::memory_order_acq_rel, std::memory_order_acquire));
    const int s = static_cast<int>(v & kSlotMask);
    std::size_t begin, end;
    chunk(count_, slots_, s, begin, end);
    (*job_)(begin, end, s);
    if (finished_.fetch_add(1, std::memory_order_acq_rel) + 1 == slots_ && !caller) {
      // The caller may be asleep on done_cv_: take the mutex so the wake-up cannot fall between
      // its check and its wait.
      std::lock_guard lock(mutex_);
      done_cv_.notify_one();
    }
  }
}

void ThreadPool::set_active(int threads) {
  active_.store(std::clamp(threads, 1, threads_), std::memory_order_relaxed);
}

void ThreadPool::run(std::size_t count, const Job& fn) {
  if (active_.load(std::memory_order_relaxed) == 1) {
    for (int s = 0; s < slots_; ++s) {
      std::size_t begin, end;
      chunk(count, slots_, s, begin, end);
      fn(begin, end, s);
    }
    return;
  }
  job_ = &fn;
  count_ = count;
  finished_.store(0, std::memory_order_relaxed);
  const unsigned long generation = generation_.load(std::memory_order_relaxed) + 1;
  next_.store(tag(generation), std::memory_order_release);
  {
    // Under the mutex, so that a helper about to sleep either sees the new generation or is
    // already waiting when it is notified.
    std::lock_guard lock(mutex_);
    generation_.store(generation, std::memory_order_release);
  }
  start_cv_.notify_all();
  take_slots(generation, true);
  auto all_done = [this] { return finished_.load(std::memory_order_acquire) == slots_; };
  if (!spin_until(all_done, kSpinNs)) {
    std::unique_lock lock(mutex_);
    done_cv_.wait(lock, all_done);
  }
}

void ThreadPool::worker_loop(int w) {
  unsigned long seen = 0;
  for (;;) {
    auto next = [&] {
      return stopping_.load(std::memory_order_relaxed) || generation_.load(std::memory_order_acquire) != seen;
    };
    if (!spin_until(next, kSpinNs)) {
      std::unique_lock lock(mutex_);
      start_cv_.wait(lock, next);
    }
    if (stopping_.load()) return;
    seen = generation_.load(std::memory_order_acquire);
    // A helper beyond the active count lets the others take the slots (it sleeps once the
    // jobs stop coming to it).
    if (w < active_.load(std::memory_order_relaxed)) take_slots(seen, false);
  }
}

}  // namespace hapfluid::sim
