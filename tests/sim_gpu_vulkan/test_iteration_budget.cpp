// The iterations a recorded step holds per solve (iteration_budget.hpp): the scene's cap until a
// window of history exists and again after a solve ran out; otherwise twice the most a solve
// took, with a margin, in multiples of 8.
#include <gtest/gtest.h>

#include "hapfluid/sim_vulkan/iteration_budget.hpp"

using hapfluid::sim::vulkan::IterationBudget;

TEST(IterationBudget, TheCapUntilAWindowOfSubmissionsHasBeenSeen) {
  IterationBudget b(100);
  for (int k = 0; k + 1 < IterationBudget::kWindow; ++k) {
    EXPECT_EQ(b.budget(), 100) << k;
    b.observe(5, false);
  }
  b.observe(5, false);
  EXPECT_EQ(b.budget(), 16);  // 2 * 5 + 4 = 14, rounded up to 16
}

TEST(IterationBudget, FollowsTheMostIterationsOfTheWindowNeverAboveTheCap) {
  IterationBudget b(40);
  for (int k = 0; k < IterationBudget::kWindow; ++k) b.observe(k == 3 ? 11 : 2, false);
  EXPECT_EQ(b.budget(), 32);  // 2 * 11 + 4 = 26 -> 32
  for (int k = 0; k < IterationBudget::kWindow; ++k) b.observe(2, false);
  EXPECT_EQ(b.budget(), 8);  // the 11 has left the window
  for (int k = 0; k < IterationBudget::kWindow; ++k) b.observe(30, false);
  EXPECT_EQ(b.budget(), 40);  // 64 capped
}

TEST(IterationBudget, ASolveThatRanOutGetsTheCapBackForAWholeWindow) {
  IterationBudget b(100);
  for (int k = 0; k < IterationBudget::kWindow; ++k) b.observe(3, false);
  ASSERT_EQ(b.budget(), 16);
  b.observe(16, true);
  for (int k = 0; k + 1 < IterationBudget::kWindow; ++k) {
    EXPECT_EQ(b.budget(), 100) << k;
    b.observe(3, false);
  }
  b.observe(3, false);
  EXPECT_EQ(b.budget(), 16);
}
