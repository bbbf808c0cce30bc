// The implicit integrator (projective.h): exact rigid motion, rest staying at rest, pins,
// agreement with the static solve, and stability at dt = 1/60 s with 100x stiffer material on
// the strike and grasp scenes.
#include <gtest/gtest.h>

#include <cmath>

#include "gradel/projective.h"
#include "gradel/scene.h"
#include "gradel/shared/validation.h"
#include "test_support.h"

namespace gradel {
namespace {

SimulationSettings implicitSettings(Real dt = 1.0 / 60.0) { return test::frameStep(IntegratorKind::Implicit, dt); }

TEST(Implicit, ParseIntegratorKindImplicitRoundTrips) {
  EXPECT_EQ(parseIntegratorKind("implicit"), IntegratorKind::Implicit);
  EXPECT_STREQ(integratorKindName(IntegratorKind::Implicit), "implicit");
}

TEST(Implicit, DtAutoIsOneFrame) {
  test::Body b = test::makeBody("sphere", 6, 3, LayoutKind::Gradational);
  SimulationSettings s = implicitSettings(0);
  World w(b.model, s, {}, {});
  EXPECT_DOUBLE_EQ(w.dt(), 1.0 / 60.0);
}

TEST(Implicit, FreeFallIsExactAndUndeformed) {
  test::Body b = test::makeBody("sphere", 6, 3, LayoutKind::Gradational);
  World w(b.model, implicitSettings(), {}, {});
  for (int i = 0; i < 30; ++i) w.step();
  // Backward Euler on gravity alone: v_n = n g dt, x_n = x_0 + n(n+1)/2 g dt^2.
  const Real dt = w.dt(), n = 30;
  for (size_t i = 0; i < b.model->numVertices(); ++i) {
    EXPECT_NEAR(w.state().velocities[i].y(), -9.81 * n * dt, 1e-9);
    EXPECT_NEAR(w.state().positions[i].y() - b.model->restPositions[i].y(), -9.81 * n * (n + 1) / 2 * dt * dt, 1e-9);
  }
}

TEST(Implicit, RestWithoutGravityStaysAtRest) {
  test::Body b = test::makeBody("sphere", 8, 3, LayoutKind::Gradational);
  World w(b.model, test::isolated(), {}, {});
  SimulationSettings s = implicitSettings();
  s.gravity.setZero();
  World wi(b.model, s, {}, {});
  for (int i = 0; i < 20; ++i) wi.step();
  for (size_t i = 0; i < b.model->numVertices(); ++i)
    EXPECT_NEAR((wi.state().positions[i] - b.model->restPositions[i]).norm(), 0, 1e-12);
}

TEST(Implicit, ClampedBarPinsHoldAndSettlesOnTheStaticSag) {
  BarSpec bar;
  bar.across = 2;
  bar.along = 8;
  bar.material.youngsModulus = 1e6;
  SimulationSettings s = implicitSettings();
  s.damping = 2;
  BuiltScene b = buildScene(barScene(bar, s));
  World& w = *b.world;
  for (int i = 0; i < 300; ++i) w.step();
  for (uint32_t i : w.pinned().vertices) EXPECT_EQ(w.state().positions[i], w.model().restPositions[i]);
  const std::vector<uint32_t> tip = tipVertices(w.model(), bar.length());
  Real sag = 0;
  for (uint32_t i : tip) sag += w.model().restPositions[i].y() - w.state().positions[i].y();
  sag /= Real(tip.size());
  const SagResult ref = staticTipSag(bar);
  EXPECT_GT(ref.sag, 0);
  EXPECT_NEAR(sag, ref.sag, 0.01 * ref.sag);
}

TEST(Implicit, EveryVertexPinnedFollowsItsPinsWithNothingToSolve) {
  // No free row: the sparse factor is empty (METIS cannot order an empty graph; projective.cpp).
  BarSpec bar;
  bar.across = 2;
  bar.along = 4;
  for (IntegratorKind kind : {IntegratorKind::Implicit, IntegratorKind::LargeStep}) {
    Scene scene = barScene(bar, test::frameStep(kind, 1.0 / 60.0));
    PinSettings all;
    all.min = Vec3::Constant(-1), all.max = Vec3::Constant(1);
    all.path.keys = {Keyframe{0, Vec3::Zero(), std::nullopt}, Keyframe{1, Vec3(0.01, 0, 0), std::nullopt}};
    scene.pins = {all};
    BuiltScene b = buildScene(scene);
    World& w = *b.world;
    ASSERT_EQ(w.pinned().vertices.size(), w.model().numVertices());
    for (int i = 0; i < 30; ++i) w.step();  // t = 0.5 s
    for (size_t i = 0; i < w.model().numVertices(); ++i)
      EXPECT_NEAR((w.state().positions[i] - w.model().restPositions[i] - Vec3(0.005, 0, 0)).norm(), 0, 1e-12)
          << integratorKindName(kind);
  }
}

std::unique_ptr<BuiltScene> runStiff(const std::string& file, Real duration) {
  return test::runStiffScene(file, duration, IntegratorKind::Implicit, 100, 1.0 / 60.0);
}
using test::centroid;

TEST(Implicit, StrikeSceneStiffAtFrameStepIsStableAndSendsTheBallAway) {
  auto b = runStiff("strike.json", 0.5);
  EXPECT_GT(centroid(*b->world).x(), 0.15);  // starts at 0.06
}
TEST(Implicit, GraspTwoSceneStiffAtFrameStepIsStableAndLifts) {
  auto b = runStiff("grasp-two.json", 1.5);
  EXPECT_GT(centroid(*b->world).y(), 0.065);  // rests at 0.06
}
TEST(Implicit, GraspWallSceneStiffAtFrameStepIsStable) { runStiff("grasp-wall.json", 1.5); }

}  // namespace
}  // namespace gradel
