#include "thread_choice.hpp"

#include <algorithm>

namespace hapfluid::sim {
namespace {

template <std::size_t N>
double median(std::array<double, N> v) {
  std::nth_element(v.begin(), v.begin() + N / 2, v.end());
  return v[N / 2];
}

}  // namespace

ThreadChoice::ThreadChoice(int threads) : threads_(threads < 1 ? 1 : threads), chosen_(threads_) {
  if (threads_ == 1) probing_ = false;
}

int ThreadChoice::next() const {
  if (!probing_) return chosen_;
  return in_phase_ % 2 == 0 ? threads_ : 1;
}

void ThreadChoice::took(double wall_s) {
  const int with = next();
  ++steps_[with == 1 && threads_ > 1 ? 1 : 0];
  if (threads_ == 1) return;
  if (!probing_) {
    held_s_ += wall_s;
    if (held_s_ >= kHoldWallS) probing_ = true, in_phase_ = 0, held_s_ = 0;
    return;
  }
  probe_wall_[in_phase_ % 2][in_phase_ / 2] = wall_s;
  if (++in_phase_ < kProbeSteps) return;
  chosen_ = median(probe_wall_[1]) < median(probe_wall_[0]) ? 1 : threads_;
  ++probes_;
  probing_ = false;
  in_phase_ = 0;
}

}  // namespace hapfluid::sim
