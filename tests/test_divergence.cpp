// Tests for the divergence guard (divergence.h): the energy budget counts what the initial state,
// gravity and manipulators can supply, and a persistent inversion is told from a brief one.
#include <gtest/gtest.h>

#include <cmath>

#include "gradel/divergence.h"

namespace gradel {
namespace {

Metrics at(double t, double kinetic, double elastic = 0, double gravity = 0, double det = 1) {
  Metrics m;
  m.time = t;
  m.kineticEnergy = kinetic;
  m.elasticEnergy = elastic;
  m.gravityEnergy = gravity;
  m.minElementDet = det;
  return m;
}

TEST(Divergence, AllowedEnergyCountsInitialGravityDropManipulatorsAndSlack) {
  EnergyBudget b;
  b.initial = at(0, 1.0, 0.5, 10.0);
  b.mass = 2.0;
  b.drivenSpeed = 3.0;
  DivergenceSettings s;
  s.energyFactor = 10;
  s.slackSpeed = 1.0;
  // 10 x (1 + 0.5 + (10 - 4) + 1/2 2 (2 3)^2 + 1/2 2 1^2) = 10 x 44.5
  EXPECT_DOUBLE_EQ(allowedEnergy(b, s, at(1, 0, 0, 4.0)), 445.0);
  // Gravity energy above the start (the body climbed) supplies nothing.
  EXPECT_DOUBLE_EQ(allowedEnergy(b, s, at(1, 0, 0, 12.0)), 385.0);
  b.unbounded = true;
  EXPECT_TRUE(std::isinf(allowedEnergy(b, s, at(1, 0))));
}

TEST(Divergence, GuardEnergyOverBudgetIsDivergedWithTheNumbersAndCause) {
  EnergyBudget b;
  b.initial = at(0, 0.0, 0.0, 2.7);
  b.mass = 1.0;
  DivergenceGuard g(b);
  EXPECT_FALSE(g.check(at(0.5, 2.0, 0.5, 0.2), "cause"));  // a fall of 2.5 J turned into motion
  const auto msg = g.check(at(0.6, 1.4e5, 10, 0.2, -5), "the likely cause is X");
  ASSERT_TRUE(msg);
  EXPECT_NE(msg->find("simulation diverged at t = 0.6 s: kinetic + elastic energy 1.4e+05 J is over 30 J"),
            std::string::npos)
      << *msg;
  EXPECT_NE(msg->find("min element det -5"), std::string::npos) << *msg;
  EXPECT_NE(msg->find("the likely cause is X"), std::string::npos) << *msg;
  EXPECT_TRUE(g.check(at(0.7, std::nan(""), 0), "c"));  // NaN energy is never plausible
}

TEST(Divergence, GuardInversionOnlyWhenPersistent) {
  EnergyBudget b;
  b.mass = 1.0;
  DivergenceSettings s;
  s.inversionFrames = 10;
  s.inversionSeconds = 0.1;
  DivergenceGuard g(b, s);
  // 9 inverted frames, then a healthy one: the count starts again.
  for (int f = 0; f < 9; ++f) EXPECT_FALSE(g.check(at(0.02 * f, 0, 0, 0, -0.1), "c"));
  EXPECT_FALSE(g.check(at(0.2, 0, 0, 0, 0.5), "c"));
  // 10 frames over less than 0.1 s are not enough either ...
  for (int f = 0; f < 10; ++f) EXPECT_FALSE(g.check(at(1 + 0.001 * f, 0, 0, 0, -0.1), "c"));
  // ... until the inversion has lasted 0.1 s.
  std::optional<std::string> msg;
  for (int f = 10; f < 200 && !msg; ++f) msg = g.check(at(1 + 0.001 * f, 0, 0, 0, -0.1), "c");
  ASSERT_TRUE(msg);
  EXPECT_NE(msg->find("elements inverted (min element det -0.1) in 101 frames running, from t = 1 to 1.1 s"),
            std::string::npos)
      << *msg;
}

TEST(Divergence, MaxPathSpeedFindsTheFastestSegmentAndTheKeptVelocity) {
  Path p;
  p.keys = {
      {0.0, Vec3(0, 0, 0), std::nullopt}, {0.1, Vec3(0.2, 0, 0), std::nullopt}, {0.5, Vec3(0.2, 0.1, 0), std::nullopt}};
  EXPECT_NEAR(maxPathSpeed(p, 1.0), 2.0, 1e-12);
  p.keys.back().velocity = Vec3(0, 0, 5);  // kept after the last key
  EXPECT_NEAR(maxPathSpeed(p, 1.0), 5.0, 1e-12);
  EXPECT_EQ(maxPathSpeed(Path{}, 1.0), 0.0);
}

}  // namespace
}  // namespace gradel
