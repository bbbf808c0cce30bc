// The thread governor (thread_team.h): which of all members or one it runs, from the step times
// it is told. Results never depend on the choice; these tests pin the decision rule.
#include <gtest/gtest.h>

#include "thread_team.h"

namespace gradel {
namespace {

// Reports one window of steps, each `seconds` long, with the mode the governor chooses, summing
// the times as the governor does so that the window ends where its own does; returns whether
// the window ran on one member.
bool window(ThreadGovernor& g, double seconds) {
  const bool one = g.choose(2) == 1;
  double t = 0;
  int steps = 0;
  do {
    EXPECT_EQ(g.choose(2) == 1, one);  // a window never changes mode half way
    g.report(seconds);
    t += seconds, ++steps;
  } while (!(t >= ThreadGovernor::kWindowSeconds && steps >= ThreadGovernor::kWindowSteps));
  return one;
}

// The run of the choice: kRunSeconds of steps in the chosen mode.
void run(ThreadGovernor& g, double seconds, int expectMembers) {
  double t = 0;
  do {
    EXPECT_EQ(g.choose(2), expectMembers);
    g.report(seconds);
    t += seconds;
  } while (t < ThreadGovernor::kRunSeconds);
}

// One slow first window with all members (a new worker sharing its creator's core) must not
// send the run to one member: the governor measures all members again before it decides.
TEST(ThreadGovernor, OneSlowWindowDoesNotSwitchToOneMember) {
  ThreadGovernor g;
  EXPECT_FALSE(window(g, 255e-6));  // all members, the slow first window
  EXPECT_TRUE(window(g, 236e-6));   // the probe of one member: faster than that window
  EXPECT_FALSE(window(g, 128e-6));  // all members again, at their real speed
  EXPECT_FALSE(g.usingOne());
  EXPECT_EQ(g.choose(2), 2);
}

// Where one member is faster in every window (another busy program on the machine), the
// governor switches to it, and back when all members are faster again.
TEST(ThreadGovernor, SwitchesWhenTheOtherModeWinsBothComparisons) {
  ThreadGovernor g;
  EXPECT_FALSE(window(g, 300e-6));
  EXPECT_TRUE(window(g, 200e-6));
  EXPECT_FALSE(window(g, 310e-6));
  EXPECT_TRUE(g.usingOne());
  // It runs the choice for kRunSeconds, then measures one, probes all, measures one again.
  run(g, 200e-6, 1);
  EXPECT_TRUE(window(g, 200e-6));
  EXPECT_FALSE(window(g, 120e-6));
  EXPECT_TRUE(window(g, 200e-6));
  EXPECT_FALSE(g.usingOne());
}

// Within the margin (5 %) the mode in use stays.
TEST(ThreadGovernor, KeepsTheModeWithinTheMargin) {
  ThreadGovernor g;
  window(g, 200e-6);
  window(g, 195e-6);
  window(g, 200e-6);
  EXPECT_FALSE(g.usingOne());
}

}  // namespace
}  // namespace gradel
