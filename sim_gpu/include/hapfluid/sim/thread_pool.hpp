// A fixed-size pool of worker threads for the CPU solver. Work is cut into a fixed number of
// slots, contiguous equal chunks of [0, count): slot s always covers the same items and writes
// only its own outputs (its neighbour list, its partial sums), whichever thread runs it, and the
// threads take the slots in turn as they come free. Results are therefore bit-for-bit identical
// from run to run, and for any thread count up to kSlots (no atomics in the physics), and a thread
// that the scheduler parks (a 1 kHz real-time task on its core, a renderer) delays one slot, not
// half of every pass.
//
// A DFSPH step hands out a hundred or more short jobs (every solver iteration is two), so a
// hand-off must cost far less than a futex wake-up: helpers and the caller spin for a short
// while (kSpinNs) on an atomic generation and count before they sleep on a condition variable.
// Between steps, and in a live sim waiting for the wall clock, the helpers sleep. A job is done
// when its slots are, not when every helper has looked at it: a helper the scheduler has parked
// (the live sim shares its cores with the 1 kHz loop and the devices) cannot hold up a job whose
// slots the others have taken, so the caller never waits for a wake-up that brings no work.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <mutex>
#include <type_traits>
#include <thread>
#include <vector>

namespace hapfluid::sim {

// The most worker threads haptic-sim runs (--threads, batch and live).
inline constexpr int kMaxWorkerThreads = 256;

// The CPUs this process may run on (its affinity: a systemd CPUAffinity=, taskset, isolated cores
// left out), at least 1: the default thread count. More threads than that would take turns on
// one CPU and wait for each other at every pass.
int usable_cpus();

class ThreadPool {
 public:
  // threads >= 1; the calling thread is worker 0, so threads - 1 helpers are started.
  explicit ThreadPool(int threads);
  ~ThreadPool();
  ThreadPool(const ThreadPool&) = delete;
  ThreadPool& operator=(const ThreadPool&) = delete;

  int size() const { return threads_; }
  // How many of the threads take part in the next jobs, 1..size() (clamped); the others sleep.
  // Any count gives the same results (the slots are fixed), so a live sim may switch between
  // jobs to whichever count runs faster beside the 1 kHz loop. Called by the owning thread only.
  void set_active(int threads);
  int active() const { return active_.load(std::memory_order_relaxed); }
  // How many slots every parallel_for cuts its range into: per-slot outputs are sized by it.
  int slots() const { return slots_; }

  // Calls fn(begin, end, slot) for each slot's chunk and returns when all are done. `fn` is
  // called through a plain reference (no std::function), so a step allocates nothing however
  // much its lambdas capture.
  template <class Fn>
  void parallel_for(std::size_t count, Fn&& fn) {
    using F = std::remove_reference_t<Fn>;
    run(count, Job{const_cast<void*>(static_cast<const void*>(&fn)),
                   [](void* f, std::size_t b, std::size_t e, int s) { (*static_cast<F*>(f))(b, e, s); }});
  }

  // The chunk slot `s` of `slots` covers for `count` items: the same split parallel_for uses.
  static void chunk(std::size_t count, int slots, int s, std::size_t& begin, std::size_t& end) {
    begin = count * static_cast<std::size_t>(s) / static_cast<std::size_t>(slots);
    end = count * static_cast<std::size_t>(s + 1) / static_cast<std::size_t>(slots);
  }

  // Slots per pass for up to this many threads (more threads: a slot each).
  static constexpr int kSlots = 16;

 private:
  struct Job {
    void* fn;
    void (*call)(void* fn, std::size_t begin, std::size_t end, int slot);
    void operator()(std::size_t begin, std::size_t end, int slot) const { call(fn, begin, end, slot); }
  };
  void run(std::size_t count, const Job& job);
  // Runs slots of job `generation` until none is left (or that job has been replaced).
  void take_slots(unsigned long generation, bool caller);
  void worker_loop(int w);

  // How long a helper waits for the next job, or the caller for the helpers, before sleeping.
  static constexpr long kSpinNs = 50'000;

  int threads_;
  int slots_;
  std::vector<std::thread> helpers_;
  std::mutex mutex_;
  std::condition_variable start_cv_, done_cv_;
  // job_ and count_ are written before next_ is released with the job's generation, and read
  // only by a thread that has claimed a slot of that generation from next_; the caller writes
  // the next job only once every slot has been counted in finished_.
  const Job* job_ = nullptr;
  std::size_t count_ = 0;
  std::atomic<std::uint64_t> next_{0};        // (generation << 32) | next free slot
  std::atomic<int> finished_{0};              // slots of the current job done
  std::atomic<unsigned long> generation_{0};  // wakes the helpers
  std::atomic<bool> stopping_{false};
  std::atomic<int> active_{1};
};

}  // namespace hapfluid::sim
