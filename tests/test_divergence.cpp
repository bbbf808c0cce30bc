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
  EXPECT_FALSE(g.check(at(0.5, 2.0, 0.5, 0.2), 0, "cause"));  // a fall of 2.5 J turned into motion
  const auto msg = g.check(at(0.6, 1.4e5, 10, 0.2, -5), 0, "the likely cause is X");
  ASSERT_TRUE(msg);
  EXPECT_NE(msg->find("simulation diverged at t = 0.6 s: kinetic + elastic energy 1.4e+05 J is over 30 J"),
            std::string::npos)
      << *msg;
  EXPECT_NE(msg->find("min element det -5"), std::string::npos) << *msg;
  EXPECT_NE(msg->find("the likely cause is X"), std::string::npos) << *msg;
  EXPECT_TRUE(g.check(at(0.7, std::nan(""), 0), 0, "c"));  // NaN energy is never plausible
}

TEST(Divergence, ContactWorkIsSuppliedEnergy) {
  // A tool placed inside a body stores the energy of pushing the material aside: counted as
  // supplied, the same energy is no divergence; 10x over it is.
  EnergyBudget b;
  b.mass = 1.0;
  DivergenceGuard g(b);
  EXPECT_TRUE(g.check(at(0.01, 0, 50), 0, "c"));    // over 10 x (1/2 1 1^2) = 5 J
  EXPECT_FALSE(g.check(at(0.01, 0, 50), 40, "c"));  // 50 J stored, 40 J of contact work
  EXPECT_TRUE(g.check(at(0.02, 0, 500), 40, "c"));  // 500 J > 10 x 40.5 J
  EXPECT_DOUBLE_EQ(allowedEnergy(b, DivergenceSettings{}, at(0, 0), 40), 405.0);
}

TEST(Divergence, GuardInversionIsAWarningOnlyWhenPersistent) {
  EnergyBudget b;
  b.mass = 1.0;
  DivergenceSettings s;
  s.inversionFrames = 10;
  s.inversionSeconds = 0.1;
  DivergenceGuard g(b, s);
  std::string warning;
  // 9 inverted frames, then a healthy one: the count starts again.
  for (int f = 0; f < 9; ++f) EXPECT_FALSE(g.check(at(0.02 * f, 0, 0, 0, -0.1), 0, "c", &warning));
  EXPECT_FALSE(g.check(at(0.2, 0, 0, 0, 0.5), 0, "c", &warning));
  // 10 frames over less than 0.1 s are not enough either ...
  for (int f = 0; f < 10; ++f) EXPECT_FALSE(g.check(at(1 + 0.001 * f, 0, 0, 0, -0.1), 0, "c", &warning));
  EXPECT_TRUE(warning.empty());
  // ... until the inversion has lasted 0.1 s: a warning, once, and never a divergence.
  for (int f = 10; f < 400; ++f) EXPECT_FALSE(g.check(at(1 + 0.001 * f, 0, 0, 0, -0.1), 0, "c", &warning));
  EXPECT_NE(warning.find("elements inverted (min element det -0.1) in 101 frames running, from t = 1 to 1.1 s"),
            std::string::npos)
      << warning;
}

TEST(Divergence, LikelyCauseNamesTheMeasuredCauseAndTheSetting) {
  DivergenceFacts f;
  f.dt = 1e-4, f.dtFraction = 0.5, f.period = 2e-4, f.stableDt = 6.4e-5, f.voxelSize = 0.01;
  std::string c = likelyCause(f, at(0, 0));
  EXPECT_NE(c.find("simulation.dt_fraction = 0.5"), std::string::npos) << c;
  EXPECT_NE(c.find("stability limit of about 6.4e-05 s"), std::string::npos) << c;
  EXPECT_NE(c.find("set simulation.dt_fraction to 0.16 or less"), std::string::npos) << c;
  f.dt = 2e-5, f.manipulatorSpeed = 1000;  // 2 voxels per step
  c = likelyCause(f, at(0, 0));
  EXPECT_NE(c.find("a manipulator moving at 1e+03 m/s, 2 voxels"), std::string::npos) << c;
  f.manipulatorSpeed = 0, f.bodySpeed = 400;
  EXPECT_NE(likelyCause(f, at(0, 0)).find("an impact at 400 m/s"), std::string::npos);
  f.bodySpeed = 1, f.stiffnessRatio = 1000, f.softE = 1e4, f.stiffE = 1e7;
  EXPECT_NE(likelyCause(f, at(0, 0)).find("stiffness ratio 1e+03"), std::string::npos);
  f.stiffnessRatio = 1;
  EXPECT_NE(likelyCause(f, at(0, 0, 0, 0, -2)).find("inverted elements (min element det -2)"), std::string::npos);
  f.forwardEuler = true;
  EXPECT_NE(likelyCause(f, at(0, 0)).find("forward_euler"), std::string::npos);
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
