// The live sim's choice of worker threads (sim_gpu/live/thread_choice.hpp), on step times given
// to it: it probes all threads and one in turn, keeps the faster, and probes again later.
#include <gtest/gtest.h>

#include "thread_choice.hpp"

using hapfluid::sim::ThreadChoice;

namespace {

// Runs `steps` steps, each taking `with_one` s at one thread and `with_all` s at all.
void run(ThreadChoice& c, int steps, double with_one, double with_all) {
  for (int k = 0; k < steps; ++k) c.took(c.next() == 1 ? with_one : with_all);
}

constexpr int kProbe = 4 * ThreadChoice::kWindowSteps;

}  // namespace

TEST(ThreadChoice, KeepsOneThreadWhereOneIsFasterAndAllWhereAllAre) {
  ThreadChoice c(2);
  EXPECT_EQ(c.next(), 2);  // probing starts with all threads
  run(c, kProbe, 2.0e-3, 2.5e-3);
  EXPECT_EQ(c.chosen(), 1);
  EXPECT_EQ(c.probes(), 1);
  run(c, ThreadChoice::kHoldSteps - 1, 2.0e-3, 2.5e-3);
  EXPECT_EQ(c.next(), 1);  // held until the next probe
  EXPECT_EQ(c.steps_with_one(), static_cast<std::uint64_t>(kProbe / 2 + ThreadChoice::kHoldSteps - 1));
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
