// The live sim's choice of worker threads (sim_gpu/live/thread_choice.hpp), on step times given
// to it: it probes all threads and one, step by step in turn, keeps the one whose median step
// was shorter, and probes again later.
#include <gtest/gtest.h>

#include <cmath>
#include <tuple>

#include "thread_choice.hpp"

using hapfluid::sim::ThreadChoice;

namespace {

// Runs `steps` steps, each taking `with_one` s at one thread and `with_all` s at all.
void run(ThreadChoice& c, int steps, double with_one, double with_all) {
  for (int k = 0; k < steps; ++k) c.took(c.next() == 1 ? with_one : with_all);
}

constexpr int kProbe = ThreadChoice::kProbeSteps;

}  // namespace

TEST(ThreadChoice, KeepsOneThreadWhereOneIsFasterAndAllWhereAllAre) {
  ThreadChoice c(2);
  EXPECT_EQ(c.next(), 2);  // probing starts with all threads
  run(c, kProbe, 2.0e-3, 2.5e-3);
  EXPECT_EQ(c.chosen(), 1);
  EXPECT_EQ(c.probes(), 1);
  // Held for kHoldWallS of steps: 1,000 steps of 2 ms.
  const int hold = static_cast<int>(std::lround(ThreadChoice::kHoldWallS / 2.0e-3));
  run(c, hold - 1, 2.0e-3, 2.5e-3);
  EXPECT_EQ(c.next(), 1);  // held until the next probe
  EXPECT_EQ(c.steps_with_one(), static_cast<std::uint64_t>(kProbe / 2 + hold - 1));
  // The fluid grows costlier (a pour lands, say): two threads now win, and the next probe says so.
  run(c, 1 + kProbe, 4.0e-3, 2.5e-3);
  EXPECT_EQ(c.chosen(), 2);
  EXPECT_EQ(c.probes(), 2);
  EXPECT_EQ(c.next(), 2);
}

TEST(ThreadChoice, OneThreadHasNothingToChoose) {
  ThreadChoice c(1);
  run(c, 5000, 1e-3, 1e-3);
  EXPECT_EQ(c.next(), 1);
  EXPECT_EQ(c.probes(), 0);
  EXPECT_EQ(c.steps_with_all(), 5000u);
}

TEST(ThreadChoice, ATieKeepsAllThreads) {
  ThreadChoice c(4);
  run(c, kProbe, 1e-3, 1e-3);
  EXPECT_EQ(c.chosen(), 4);
}

TEST(ThreadChoice, TheProbeAlternatesStepByStep) {
  ThreadChoice c(2);
  for (int k = 0; k < kProbe; ++k) {
    ASSERT_EQ(c.next(), k % 2 == 0 ? 2 : 1) << "step " << k;
    c.took(1e-3);
  }
}

// Another process takes the cores for a while (the renderer starting, a burst of I/O): steps
// then take several times longer whatever the thread count. Two threads are faster here; a burst
// of 15 slow steps anywhere in the probe must not make it choose one, and the same burst must
// not hide that one is faster where it is.
TEST(ThreadChoice, ABurstOfLoadDuringTheProbeDoesNotDecideIt) {
  constexpr int kBurst = 15;
  constexpr double kBurstStep = 20e-3;
  for (int start = 0; start + kBurst <= kProbe; start += 5) {
    for (const auto& [with_one, with_all, expected] : {std::tuple{3.0e-3, 2.5e-3, 2}, std::tuple{2.5e-3, 3.0e-3, 1}}) {
      ThreadChoice c(2);
      for (int k = 0; k < kProbe; ++k) {
        const bool burst = k >= start && k < start + kBurst;
        c.took(burst ? kBurstStep : (c.next() == 1 ? with_one : with_all));
      }
      EXPECT_EQ(c.chosen(), expected) << "burst from probe step " << start << ", one thread " << with_one * 1e3
                                      << " ms, all " << with_all * 1e3 << " ms";
    }
  }
}
