// Tests for start overlaps (issue 26, overlaps.h): bodies placed overlapping each other, a wall
// or a manipulator are found at t = 0 and separated at kStartSeparationSpeed (1 m/s) within
// depth / speed, with no energy beyond what the moving walls and tools store (counted as the
// contacts' work) and, between bodies, none at all and the momentum kept.
#include <gtest/gtest.h>

#include <cmath>

#include "gradel/divergence.h"
#include "gradel/overlaps.h"
#include "gradel/scene.h"
#include "test_support.h"

namespace gradel {
namespace {

BuiltScene build(const std::string& json) { return buildScene(parseScene(json, "test.json")); }

TEST(StartOverlap, BodiesHalfInsideEachOtherSeparateWithoutEnergyMomentumKept) {
  // Two 12^3 balls (12 cm) whose centres are 6 cm apart: half inside each other, moving at
  // +-0.2 m/s, no gravity, no damping.
  BuiltScene b = build(R"({
    "bodies": [
      {"name": "left", "shape": "sphere", "size": 12, "voxel_size": 0.01, "position": [-0.09, -0.06, -0.06], "velocity": [0.2, 0, 0]},
      {"name": "right", "shape": "sphere", "size": 12, "voxel_size": 0.01, "position": [-0.03, -0.06, -0.06], "velocity": [-0.2, 0.1, 0]}],
    "simulation": {"damping": 0, "gravity": [0, 0, 0]},
    "body_contact": {"restitution": 0.5}})");
  World& w = *b.world;
  const std::vector<StartOverlap> found = w.startOverlaps();
  ASSERT_EQ(found.size(), 1u);
  EXPECT_EQ(found[0].with, StartOverlap::With::Body);
  EXPECT_NEAR(found[0].depth, 0.06, 1e-9);  // the balls' extents along x overlap by 6 cm
  EXPECT_NEAR(found[0].direction.x(), 1.0, 1e-9);
  const std::string text = describeStartOverlap(found[0], w, {"left", "right"});
  EXPECT_NE(text.find("body 'left' and body 'right' start overlapping"), std::string::npos) << text;
  const Metrics m0 = w.metrics();
  const Real e0 = m0.kineticEnergy + m0.elasticEnergy;
  const Vec3 p0 = test::momentum(w);
  // Separated within depth / speed (+ a step).
  Real peak = 0, separatedAt = -1;
  while (w.time() < 0.2) {
    w.step();
    const Metrics m = w.metrics();
    peak = std::max(peak, m.kineticEnergy + m.elasticEnergy);
    if (separatedAt < 0 && !w.separatingStartOverlaps()) separatedAt = w.time();
    EXPECT_LT((test::momentum(w) - p0).norm(), 1e-9 * (p0.norm() + 1e-3));
  }
  std::printf("[ measured ] separated at t = %.4g s (bound 0.06 s); energy %.4g J at the start, peak %.4g J\n",
              separatedAt, e0, peak);
  ASSERT_GT(separatedAt, 0);
  // The bounds: the overlap over the separation speed, plus the closing speed of 0.4 m/s
  // (compensated while they separate): 0.06 m / 1 m/s.
  EXPECT_LE(separatedAt, 0.06 / kStartSeparationSpeed + 2 * w.dt());
  EXPECT_EQ(test::verticesInsideOtherBodies(w), 0u);
  // No energy from the separation (a rigid move of each body): what rises is the elastic energy
  // of the contact that follows at 0.4 m/s (measured peak 1.064 e0 on the sanitizer build,
  // 1.050-1.064 across builds); a separation that pushed the bodies apart elastically stored
  // x12,800 (issue 26).
  EXPECT_LE(peak, 1.10 * e0);
  EXPECT_EQ(w.contactWork(), 0.0);
}

TEST(StartOverlap, BallAcrossTheFloorIsPushedOutAtTheCappedSpeed) {
  // A 12^3 ball 3 cm below the floor (y = 0), gravity on, damping 2/s.
  BuiltScene b = build(R"({
    "body": {"shape": "sphere", "size": 12, "voxel_size": 0.01, "position": [-0.06, -0.03, -0.06]},
    "simulation": {"damping": 2},
    "domain": {"min": [-0.3, 0, -0.3], "max": [0.3, 1, 0.3], "restitution": 0.3}})");
  World& w = *b.world;
  const std::vector<StartOverlap> found = w.startOverlaps();
  ASSERT_EQ(found.size(), 1u);
  EXPECT_EQ(found[0].with, StartOverlap::With::Wall);
  EXPECT_EQ(std::string(wallName(int(found[0].other))), "ymin");
  EXPECT_NEAR(found[0].depth, 0.03, 1e-9);
  const Real duration = 1.0;
  DivergenceGuard guard(energyBudget(w, duration));
  Real peak = 0, releasedAt = -1;
  while (w.time() < duration) {
    w.step();
    if (releasedAt < 0 && !w.separatingStartOverlaps()) releasedAt = w.time();
    if (std::fmod(w.time(), 0.01) < w.dt()) {
      const Metrics m = w.metrics();
      peak = std::max(peak, m.kineticEnergy + m.elasticEnergy);
      EXPECT_FALSE(guard.check(m, w.contactWork(), "c"));
    }
  }
  Real lowest = 1;
  for (const Vec3& x : w.state().positions) lowest = std::min(lowest, x.y());
  std::printf("[ measured ] floor back at t = %.4g s (bound 0.03 s); peak kinetic + elastic %.4g J, contact work %.4g "
              "J\n",
              releasedAt, peak, w.contactWork());
  EXPECT_LE(releasedAt, 0.03 / kStartSeparationSpeed + 2 * w.dt());
  EXPECT_GE(lowest, 0.0);
  EXPECT_GT(w.metrics().minElementDet, 0);
  // Pushing 3 cm at 1 m/s stores about what a 1 m/s push gives a 0.9 kg ball, not the x12,800 of an instant one.
  EXPECT_LT(peak, 2.0);
}

TEST(StartOverlap, ManipulatorInsideABodyStartsShrunkAndGrowsBack) {
  BuiltScene b = build(R"({
    "body": {"shape": "sphere", "size": 12, "voxel_size": 0.01, "position": [-0.06, -0.06, -0.06]},
    "simulation": {"damping": 2, "gravity": [0, 0, 0]},
    "manipulators": [{"type": "sphere", "radius": 0.02, "path": [{"t": 0, "position": [0.001, 0.002, 0.003]}]}]})");
  World& w = *b.world;
  const std::vector<StartOverlap> found = w.startOverlaps();
  ASSERT_EQ(found.size(), 1u);
  EXPECT_EQ(found[0].with, StartOverlap::With::Manipulator);
  // Shrunk until no vertex is inside (the coarse elements at the centre have their corners 1.7 cm away).
  EXPECT_LT(w.manipulators()[0].settings.radius, 0.018);
  Real grownAt = -1;
  while (w.time() < 0.1) {
    w.step();
    if (grownAt < 0 && !w.separatingStartOverlaps()) grownAt = w.time();
  }
  EXPECT_EQ(w.manipulators()[0].settings.radius, 0.02);
  EXPECT_LE(grownAt, 0.02 / kStartSeparationSpeed + 2 * w.dt());
  EXPECT_GT(w.contactWork(), 0);
  for (const Vec3& x : w.state().positions) EXPECT_GE(w.manipulators()[0].signedDistance(x, nullptr), -1e-9);
}

TEST(StartOverlap, TouchingBodiesAreNoOverlap) {
  // The shipped two-balls scene: 2 mm apart; and two boxes sharing a face.
  BuiltScene b = build(R"({
    "bodies": [
      {"shape": "box", "size": 4, "voxel_size": 0.01, "position": [0, 0, 0]},
      {"shape": "box", "size": 4, "voxel_size": 0.01, "position": [0.04, 0, 0]}],
    "simulation": {"gravity": [0, 0, 0]}, "body_contact": {}})");
  EXPECT_TRUE(b.world->startOverlaps().empty());
  EXPECT_TRUE(findStartOverlaps(*b.world).empty());
}

}  // namespace
}  // namespace gradel
