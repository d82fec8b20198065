// How many worker threads a live CPU sim steps fastest with, measured while it runs.
//
// The live sim shares its cores with the 1 kHz loop and the devices (SCHED_FIFO). A helper
// thread on the loop's core is preempted while it holds a slot of a pass, and the pass waits
// for it; the scheduler may also put both threads on one core. One thread then beats two, and
// which count wins changes as the run goes on (sim_gpu/README.md). Any thread count gives the
// same results (thread_pool.hpp), so switching is invisible to the physics.
//
// After every kHoldWallS seconds of steps it probes: kProbeSteps steps alternating all threads
// and one, step by step, so that the flow's drift and a burst of load from other processes fall
// on both alike. It keeps the count whose median step was shorter (all threads on a tie) until
// the next probe. The hold is wall time, not steps: where the scheduler puts the threads changes
// within seconds, whatever the step's length. Fixed storage: nothing is allocated per step.
#pragma once

#include <array>
#include <cstdint>

namespace hapfluid::sim {

class ThreadChoice {
 public:
  static constexpr int kProbeSteps = 50;
  static constexpr double kHoldWallS = 2.0;
  static_assert(kProbeSteps % 2 == 0, "a probe takes as many steps at each count");

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
  bool probing_ = true;
  int in_phase_ = 0;     // steps taken in this probe
  double held_s_ = 0;    // wall time of the steps since the last probe
  // Step wall times of the probe: [0] at all threads, [1] at one.
  std::array<std::array<double, kProbeSteps / 2>, 2> probe_wall_{};
  std::array<std::uint64_t, 2> steps_{};
  int probes_ = 0;
};

}  // namespace hapfluid::sim
