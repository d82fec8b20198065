// How many worker threads a live CPU sim steps fastest with, measured while it runs.
//
// The live sim shares its cores with the 1 kHz loop and the devices (SCHED_FIFO). A helper
// thread on the loop's core is preempted while it holds a slot of a pass, and the pass waits
// for it: for a small fluid one thread can beat two, for a large one two win (sim_gpu/README.md).
// Any thread count gives the same results (thread_pool.hpp), so switching is invisible to the
// physics. Every kHoldSteps steps it times kWindowSteps steps at all threads, then at one, twice
// over (A B A B: the flow changes little within it), and keeps the faster until the next probe.
#pragma once

#include <array>
#include <cstdint>

namespace hapfluid::sim {

class ThreadChoice {
 public:
  static constexpr int kWindowSteps = 25;
  static constexpr int kHoldSteps = 1000;

  // threads: the solver's worker threads; with one there is nothing to choose.
  explicit ThreadChoice(int threads);

  // The thread count to step with next, then the wall time that step took.
  int next() const;
  void took(double wall_s);

  int chosen() const { return chosen_; }
  int threads() const { return threads_; }
  std::uint64_t steps_with_all() const { return steps_[0]; }
  std::uint64_t steps_with_one() const { return steps_[1]; }
  int probes() const { return probes_; }

 private:
  int threads_;
  int chosen_;
  int window_ = 0;      // probing: 0..3 (all, one, all, one); holding: -1
  int in_window_ = 0;   // steps taken in this window or hold
  std::array<double, 2> probe_wall_{};  // summed step wall time at all threads, at one
  std::array<std::uint64_t, 2> steps_{};
  int probes_ = 0;
};

}  // namespace hapfluid::sim
