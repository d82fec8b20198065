// How many iterations of a solve a recorded step holds. Every recorded iteration costs a
// dispatch and a barrier even once the solve has converged (its group count is then zero), so
// recording max_solver_iterations of each solve every step spends most of a step on empty
// iterations. A budget of twice the most iterations the solve took over the last submissions,
// plus a margin, holds every solve of a steady run; until that history exists, and again after
// a solve ran out of its budget, the budget is the scene's cap, as on the CPU. A solve that runs
// out of a smaller budget ends unconverged there (counted, and the step's residual error is
// corrected by the next step's solve).
#pragma once

#include <algorithm>
#include <array>

namespace hapfluid::sim::vulkan {

class IterationBudget {
 public:
  static constexpr int kWindow = 32;  // submissions of history

  explicit IterationBudget(int cap) : cap_(cap) {}

  int budget() const {
    if (filled_ < kWindow) return cap_;
    const int most = *std::max_element(recent_.begin(), recent_.end());
    // A multiple of 8, so that a handful of budgets (and recorded command buffers) cover a run.
    return std::min(cap_, (2 * most + 4 + 7) / 8 * 8);
  }

  // After a submission: the most iterations one of its solves took, and whether one ran out of
  // a budget below the cap.
  void observe(int most_iterations, bool ran_out) {
    if (ran_out) {
      filled_ = 0;
      next_ = 0;
      return;
    }
    recent_[next_] = most_iterations;
    next_ = (next_ + 1) % kWindow;
    filled_ = std::min(filled_ + 1, kWindow);
  }

 private:
  int cap_;
  std::array<int, kWindow> recent_{};
  int filled_ = 0, next_ = 0;
};

}  // namespace hapfluid::sim::vulkan
