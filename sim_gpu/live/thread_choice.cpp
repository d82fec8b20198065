#include "thread_choice.hpp"

namespace hapfluid::sim {

ThreadChoice::ThreadChoice(int threads) : threads_(threads < 1 ? 1 : threads), chosen_(threads_) {
  if (threads_ == 1) window_ = -1;
}

int ThreadChoice::next() const {
  if (window_ < 0) return chosen_;
  return window_ % 2 == 0 ? threads_ : 1;
}

void ThreadChoice::took(double wall_s) {
  const int with = next();
  ++steps_[with == 1 && threads_ > 1 ? 1 : 0];
  if (threads_ == 1) return;
  ++in_window_;
  if (window_ < 0) {
    if (in_window_ >= kHoldSteps) window_ = 0, in_window_ = 0, probe_wall_ = {};
    return;
  }
  probe_wall_[window_ % 2] += wall_s;
  if (in_window_ < kWindowSteps) return;
  in_window_ = 0;
  if (++window_ < 4) return;
  // Equal step counts at each: the smaller sum is the faster count (all threads on a tie).
  chosen_ = probe_wall_[1] < probe_wall_[0] ? 1 : threads_;
  ++probes_;
  window_ = -1;
}

}  // namespace hapfluid::sim
