// The viewer's pacing (shared/step_pacer.h), its rates over the last second (shared/rate_window.h)
// and its size estimate (shared/realtime_size.h), driven by made-up clocks and costs: no timing.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "gradel/shared/rate_window.h"
#include "gradel/shared/realtime_size.h"
#include "gradel/shared/step_pacer.h"

using namespace gradel;

TEST(StepPacer, OwesRealTimeInBatchesThatFitTheBudget) {
  StepPacer p(1e-4, 1.0);  // 10,000 steps per wall second wanted
  p.restart(0);
  EXPECT_EQ(p.due(0), 0);
  EXPECT_EQ(p.due(0.00015), 1);  // no cost measured yet: one step
  p.stepped(1, 1e-5);            // 10 us per step: the 4 ms budget fits 400
  EXPECT_EQ(p.due(0.01005), 99);  // 100.5 owed in all, 1 taken
  p.stepped(99, 99e-5);
  EXPECT_EQ(p.due(0.01005), 0);
  EXPECT_NEAR(p.waitSeconds(0.01005), 0.5e-4, 1e-9);
  // 0.05 s later about 500 steps are owed; a batch holds at most the budget's 400.
  const long n = p.due(0.06);
  EXPECT_GE(n, 399);
  EXPECT_LE(n, 400);
  p.stepped(n, double(n) * 1e-5);
  EXPECT_EQ(p.due(0.06), 500 - n);
  EXPECT_FALSE(p.behind(0.06));
}

TEST(StepPacer, SimulatedTimeFollowsWallTimeWhenFastEnough) {
  StepPacer p(2e-4, 0.5);
  p.restart(10);
  long steps = 0;
  for (int frame = 1; frame <= 600; ++frame) {  // 10 wall seconds at 60 frames per second
    const double now = 10 + frame / 60.0;
    for (long n; (n = p.due(now)) > 0;) p.stepped(n, n * 1e-6), steps += n;
  }
  EXPECT_NEAR(steps * 2e-4, 0.5 * 10, 2e-4);  // simulated = speed x wall, to one step
  EXPECT_FALSE(p.behind(20));
  EXPECT_NEAR(p.capacity(), 2e-4 / 1e-6, 1e-3);
}

TEST(StepPacer, DropsTheDebtWhenTooSlowAndSaysSo) {
  StepPacer p(1e-4, 1.0);  // each step costs 1 ms: 0.1x real time at best
  p.restart(0);
  long steps = 0;
  double now = 0;
  for (int k = 0; k < 3000; ++k) {
    const long n = p.due(now);
    ASSERT_LE(n, 4);  // never more than the 4 ms budget's worth
    if (n == 0) {
      now += p.waitSeconds(now);
      continue;
    }
    p.stepped(n, n * 1e-3);
    now += n * 1e-3, steps += n;
  }
  EXPECT_TRUE(p.behind(now));
  // Simulated time is what the machine managed (0.1x), not caught up later.
  EXPECT_NEAR(steps * 1e-4 / now, 0.1, 1e-3);
  // Once it is fast again nothing old is owed: at most the lag limit's worth (0.1 s = 1,000 steps).
  long caughtUp = 0;
  for (long n; (n = p.due(now)) > 0;) p.stepped(n, 0), caughtUp += n;
  EXPECT_LE(caughtUp, 1001);
  EXPECT_FALSE(p.behind(now + 1.5));
}

TEST(StepPacer, NothingOwedForAPauseOrBeforeASpeedChange) {
  StepPacer p(1e-3, 1.0);
  p.restart(0);
  p.stepped(p.due(0.01), 1e-6);
  p.restart(5);  // resumed after 5 s paused
  EXPECT_EQ(p.due(5), 0);
  p.setSpeed(2.0, 5);
  EXPECT_EQ(p.due(5.01025), 20);  // 20.5 owed at 2x
  EXPECT_THROW(StepPacer(0, 1), std::invalid_argument);
}

TEST(RateWindow, RealTimeFactorIsTheLastSecondsRatio) {
  RateWindow r(1.0);
  EXPECT_EQ(r.realTimeFactor(), 0);
  // 2 s at 14x, then 3 s at 0.016x: the figure is 0.016 once the window holds only the slow part.
  double sim = 0;
  long steps = 0;
  for (int f = 0; f <= 500; ++f) {
    const double wall = f * 0.01;
    r.add(wall, sim, steps);
    sim += 0.01 * (wall < 2 ? 14 : 0.016), steps += 1;
  }
  EXPECT_NEAR(r.realTimeFactor(), 0.016, 1e-9);
  EXPECT_NEAR(r.stepsPerSecond(), 100, 1e-6);
  EXPECT_NEAR(r.samplesPerSecond(), 100, 1e-6);
  EXPECT_NEAR(r.span(), 1.0, 0.011);
  r.reset();
  EXPECT_EQ(r.realTimeFactor(), 0);
}

TEST(RealtimeSize, CapacityFallsWithSizeToThePowerPPlusOne) {
  // Measured 8x real time at size 32, gradational (p = 2.2): size 64 has 2^3.2 = 9.2x the cost.
  const SizeEstimate e = estimateSize(32, 8.0, 64, vertexExponent(LayoutKind::Gradational), 4, 256);
  EXPECT_NEAR(e.realTimeFactor, 8.0 / std::pow(2.0, 3.2), 1e-9);
  EXPECT_EQ(e.largestRealTime, int(32 * std::pow(8.0, 1 / 3.2)));  // 61
  EXPECT_EQ(estimateSize(12, 0.5, 12, 3.0, 4, 256).largestRealTime, 10);
  EXPECT_EQ(estimateSize(12, 1e-6, 12, 3.0, 4, 256).largestRealTime, 4);  // none: the smallest
  EXPECT_EQ(estimateSize(12, 1e9, 12, 3.0, 4, 256).largestRealTime, 256);
  EXPECT_EQ(vertexExponent(LayoutKind::Uniform), 3.0);
  EXPECT_THROW(estimateSize(12, 0, 12, 3.0, 4, 256), std::invalid_argument);
}
