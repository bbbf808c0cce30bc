// Physical validity (validation.h), the fast parts of `gradel-validate`: a small clamped
// cantilever against its references. Consistent scaling, E = 1e7 Pa, a = 2 cm, L = 8 a.
#include <gtest/gtest.h>

#include <cmath>

#include "gradel/validation.h"

namespace gradel {
namespace {

BarSpec bar(LayoutKind layout, int across) {
  BarSpec b;
  b.across = across;
  b.along = 8 * across;
  b.width = 0.02;
  b.layout = layout;
  b.material.youngsModulus = 1e7;
  b.material.density = 1000;
  return b;
}

TEST(Cantilever, StretchModulusConsistentScalingIsTheMaterialsE) {
  EXPECT_NEAR(stretchModulus(bar(LayoutKind::Uniform, 4)) / 1e7, 1.0, 0.02);
  EXPECT_NEAR(stretchModulus(bar(LayoutKind::Gradational, 4)) / 1e7, 1.0, 0.02);
}

// The gradational bar's coarse interior is made of incomplete elements (fig. 6) whose filled
// cells form lines and plates along the bar. With k_e = E V_e / lambda_max(S_e) (material.h) they
// are exact along the bar: measured 1.000 E at 8 across and 0.962 E at 16 (the former
// trace rule, k_e = 3 E V_e / tr S_e, measured 1.152 and 1.205). Never stiffer than E.
TEST(Cantilever, StretchModulusGradationalBarIsWithin5PercentOfE) {
  const Real e8 = stretchModulus(bar(LayoutKind::Gradational, 8)) / 1e7;
  const Real e16 = stretchModulus(bar(LayoutKind::Gradational, 16)) / 1e7;
  EXPECT_NEAR(e8, 1.0, 0.01);
  EXPECT_GT(e16, 0.95);
  EXPECT_LT(e16, 1.0 + 1e-6);
}

// Measured 0.677 of Euler-Bernoulli at 4 voxels (2 elements) across; it converges from below
// (0.90 at 8, 0.98 at 16: docs/validation/report.md). A change here changes the physics.
TEST(Cantilever, StaticTipSagUniform4MatchesItsReference) {
  const BarSpec b = bar(LayoutKind::Uniform, 4);
  const Real eb = beamTipSag(b.length(), b.width, 1000, 1e7);
  const SagResult r = staticTipSag(b);
  EXPECT_NEAR(r.sag / eb, 0.677, 0.01);
}

// Sag and first frequency of one model obey Euler-Bernoulli's omega1^2 sag = 1.875^4 g / 8
// whatever its stiffness: the free vibration and the static solve agree with each other.
TEST(Cantilever, FrequencyAndSagObeyTheBeamRelation) {
  const BarSpec b = bar(LayoutKind::Uniform, 4);
  SimulationSettings sim;
  sim.damping = 0;
  BuiltScene built = buildScene(barScene(b, sim));
  World& w = *built.world;
  const std::vector<uint32_t> tip = tipVertices(w.model(), b.length());
  std::vector<Real> y;
  const Real f0 = beamFrequency(b.length(), b.width, 1000, 1e7);
  const int every = 4;
  while (w.time() < 4 / f0) {
    for (int k = 0; k < every; ++k) w.step();
    Real s = 0;
    for (uint32_t i : tip) s += w.state().positions[i].y() - w.model().restPositions[i].y();
    y.push_back(s / Real(tip.size()));
  }
  const Real f = dominantFrequency(y, every * w.dt());
  const Real omega = 2 * 3.141592653589793 * f;
  const Real sag = staticTipSag(b).sag;
  EXPECT_NEAR(omega * omega * sag / 9.81, std::pow(1.875104, 4) / 8, 0.03 * std::pow(1.875104, 4) / 8);
}

// Gradational against uniform at the same finest resolution (8 voxels across): the issue's
// 5 % target; measured 0.3 % less sag (5.0 % less with the former trace rule for k_e).
TEST(Cantilever, StaticTipSagGradationalNearUniform) {
  const Real g = staticTipSag(bar(LayoutKind::Gradational, 8)).sag;
  const Real u = staticTipSag(bar(LayoutKind::Uniform, 8)).sag;
  EXPECT_NEAR(g / u, 1.0, 0.015);
}

}  // namespace
}  // namespace gradel
