// shared/frame_loop.h: the frame schedule and loop of `gradel run` and `gradel render`.
#include <gtest/gtest.h>

#include <limits>
#include <stdexcept>
#include <vector>

#include "gradel/shared/frame_loop.h"
#include "gradel/shared/step_batch.h"
#include "test_support.h"

using namespace gradel;
using namespace gradel::test;

namespace {
World smallWorld(Real dt) {
  Body b = makeBody("box", 4, 3, LayoutKind::Gradational);
  SimulationSettings s;  // gravity on: the body moves, so equal hashes mean equal steps
  s.dt = dt;
  s.threads = 1;
  return World(b.model, s, {}, {});
}
}  // namespace

// Frame 0 at the start, one every interval, the last exactly at the end; an interval below dt
// becomes dt; a count runs past the duration.
TEST(FrameLoop, Schedule) {
  const FrameSchedule s = frameSchedule(0, 0.1, 0.03, 0.001);
  EXPECT_EQ(s.frames, 5u);
  EXPECT_FALSE(s.intervalRaisedToDt);
  EXPECT_DOUBLE_EQ(s.time(3), 0.09);
  EXPECT_EQ(s.time(4), 0.1);
  EXPECT_EQ(frameSchedule(0, 0.1, 0.025, 0.001).frames, 5u);  // a whole number of intervals: no extra frame
  const FrameSchedule fine = frameSchedule(0, 0.0253, 1e-6, 0.001);
  EXPECT_TRUE(fine.intervalRaisedToDt);
  EXPECT_EQ(fine.frames, 27u);
  const FrameSchedule counted = frameSchedule(1.0, 0.1, 0.05, 0.001, 10);
  EXPECT_EQ(counted.frames, 10u);
  EXPECT_DOUBLE_EQ(counted.time(9), 1.45);
  EXPECT_THROW(frameSchedule(0, 10, 1e-6, 1e-7), InputError);  // 10^7 frames
  EXPECT_THROW(frameSchedule(0, 1, 0.1, 0.01, 0), InputError);
}

// The loop takes the same steps as advancing to the end at once, writes a frame at each frame
// time (on a step), skips a last frame time no step reaches, and stops when a check throws.
TEST(FrameLoop, SameStepsAsAdvanceToFramesOnDistinctSteps) {
  const Real dt = 1.0 / 1024;
  World a = smallWorld(dt), b = smallWorld(dt);
  // 100 steps every 5 steps is 20 frames after frame 0; the end 100.3 steps is 0.3 steps past
  // the last one: no step reaches it, no repeated frame.
  const FrameSchedule s = frameSchedule(0, 100.3 * dt, 5 * dt, dt);
  EXPECT_EQ(s.frames, 22u);
  std::vector<Real> times;
  int chunks = 0;
  FrameLoopChecks checks;
  checks.afterChunk = [&] { ++chunks; };
  const size_t written = runFrames(
      a, s,
      [&](size_t index) {
        EXPECT_EQ(index, times.size());
        times.push_back(a.time());
      },
      checks);
  EXPECT_EQ(written, 21u);
  ASSERT_EQ(times.size(), 21u);
  for (size_t f = 0; f < times.size(); ++f) EXPECT_NEAR(times[f], Real(5 * f) * dt, 1e-12);
  EXPECT_EQ(chunks, 20);
  b.advanceTo(100.3 * dt);
  EXPECT_EQ(a.time(), b.time());
  EXPECT_EQ(a.stateHash(), b.stateHash());

  // A check that throws stops the run within the frame (chunks of at most 32 steps).
  World c = smallWorld(dt);
  checks.afterChunk = [&] { throw std::runtime_error("stop"); };
  EXPECT_THROW(runFrames(
                   c, frameSchedule(0, 1.0, 0.5, dt), [](size_t) {}, checks),
               std::runtime_error);
  EXPECT_NEAR(c.time(), 32 * dt, 1e-12);
}

// shared/step_batch.h, the real-time front ends' batch (viewer, web page): the same steps as
// plain World::step calls, the hook before each with the batch's fraction, a budget that cuts it.
TEST(StepBatch, TakesTheStepsWithTheHookBeforeEach) {
  EXPECT_EQ(stepsFor(0.0166, 0.001), 17);
  EXPECT_EQ(stepsFor(0, 0.01), 1);  // at least one
  World a = smallWorld(1e-3), b = smallWorld(1e-3);
  std::vector<double> fractions;
  StepBatchOptions o;
  o.beforeStep = [&](double f) { fractions.push_back(f); };
  const StepBatch r = stepBatch(a, 4, o);
  for (int k = 0; k < 4; ++k) b.step();
  EXPECT_EQ(r.steps, 4);
  EXPECT_FALSE(r.cut);
  EXPECT_TRUE(r.finite);
  EXPECT_EQ(fractions, (std::vector<double>{0.25, 0.5, 0.75, 1.0}));
  EXPECT_EQ(a.state().positions, b.state().positions);
  // A budget no step fits: one step, then cut.
  o.budgetSeconds = 1e-12;
  const StepBatch cut = stepBatch(a, 4, o);
  EXPECT_EQ(cut.steps, 1);
  EXPECT_TRUE(cut.cut);
  // A non-finite state is reported.
  a.state().velocities[0].x() = std::numeric_limits<Real>::quiet_NaN();
  EXPECT_FALSE(stepBatch(a, 2).finite);
}
