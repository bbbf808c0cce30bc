// Stress in physical units (element_strain.h, issue 28): the von Mises stress [Pa] of each
// element from its strain about its best-fit rotation and its region's Young's modulus.
#include <gtest/gtest.h>

#include <cmath>

#include "gradel/element_strain.h"
#include "gradel/projective.h"
#include "gradel/shared/validation.h"
#include "test_support.h"

namespace gradel {
namespace {

// The bar with both end faces pinned, the far one moved by strain L along x, in static
// equilibrium (as validation.h stretchModulus): a uniform uniaxial stretch of the element model.
BuiltScene stretchedBar(const BarSpec& bar, Real strain) {
  SimulationSettings sim;
  sim.gravity.setZero();
  Scene scene = barScene(bar, sim, true);
  const Real L = bar.length();
  PinSettings far = barFacePin(bar, L);
  far.path.keys = {Keyframe{0, Vec3(strain * L, 0, 0), std::nullopt}};
  scene.pins.push_back(far);
  BuiltScene b = buildScene(scene);
  World& w = *b.world;
  std::vector<Vec3> targets;
  for (uint32_t i : w.pinned().vertices) targets.push_back(w.state().positions[i]);
  for (Vec3& x : w.state().positions) x.x() *= 1 + strain;
  ProjectiveSolver solver(w.model(), 0, w.pinned().vertices);
  solver.solveStatic(w.state().positions, w.state().rotations, Vec3::Zero(), targets, 20000, 1e-14 * L);
  return b;
}

// The elements whose rest centroid lies in the bar's middle half (away from the pinned ends).
std::vector<size_t> middleElements(const RestModel& m, Real L) {
  std::vector<size_t> r;
  for (size_t e = 0; e < m.numElements(); ++e) {
    Vec3 c = Vec3::Zero();
    for (uint32_t p = m.elemStart[e]; p < m.elemStart[e + 1]; ++p) c += m.restPositions[m.elemVerts[p]];
    c /= Real(m.elemStart[e + 1] - m.elemStart[e]);
    if (c.x() > 0.25 * L && c.x() < 0.75 * L) r.push_back(e);
  }
  return r;
}

TEST(ElementStrain, VonMisesOfTheTextbookStates) {
  const Real E = 2e6, e = 1e-3;
  Mat3 uniaxial = Mat3::Zero();
  uniaxial(0, 0) = e;
  EXPECT_NEAR(vonMisesStress(uniaxial, E, 0), E * e, 1e-9 * E * e);
  // With nu, a uniaxial stress state has lateral strain -nu e: still sigma_xx = E e, von Mises E e.
  const Real nu = 0.3;
  Mat3 lateral = uniaxial;
  lateral(1, 1) = lateral(2, 2) = -nu * e;
  EXPECT_NEAR(vonMisesStress(lateral, E, nu), E * e, 1e-9 * E * e);
  // Pure shear eps_xy = g / 2: tau = mu g, von Mises sqrt(3) tau.
  Mat3 shear = Mat3::Zero();
  shear(0, 1) = shear(1, 0) = e / 2;
  EXPECT_NEAR(vonMisesStress(shear, E, 0), std::sqrt(3.0) * E / 2 * e, 1e-9 * E * e);
  // A uniform expansion is pure pressure: no von Mises stress.
  EXPECT_NEAR(vonMisesStress(e * Mat3::Identity(), E, nu), 0, 1e-9 * E * e);
  EXPECT_THROW(vonMisesStress(uniaxial, E, 0.5), std::invalid_argument);
}

TEST(ElementStrain, BarUnderUniformStretchGivesYoungsModulusTimesStrain) {
  for (LayoutKind layout : {LayoutKind::Uniform, LayoutKind::Gradational}) {
    BarSpec bar;
    bar.across = 4, bar.along = 24, bar.width = 0.04, bar.layout = layout;
    bar.material.youngsModulus = 1e6;
    const Real strain = 1e-3;
    BuiltScene b = stretchedBar(bar, strain);
    const World& w = *b.world;
    const std::vector<Real> s = w.elementStress();
    ASSERT_EQ(s.size(), w.model().numElements());
    const std::vector<size_t> middle = middleElements(w.model(), bar.length());
    ASSERT_GT(middle.size(), 4u);
    Real mean = 0;
    for (size_t e : middle) {
      EXPECT_NEAR(s[e], 1e6 * strain, 0.05 * 1e6 * strain) << "element " << e << " layout " << int(layout);
      mean += s[e];
    }
    mean /= Real(middle.size());
    EXPECT_NEAR(mean, 1e6 * strain, 0.02 * 1e6 * strain) << "layout " << int(layout);
    // The old measure is still there under its own name, dimensionless and nonzero.
    const std::vector<Real> strainMeasure = w.elementStrain();
    EXPECT_GT(strainMeasure[middle.front()], 0);
    EXPECT_LT(strainMeasure[middle.front()], 10 * strain);
    const Metrics m = w.metrics();
    EXPECT_GE(m.maxStress, mean);
    EXPECT_GT(m.maxStrain, 0);
  }
}

TEST(ElementStrain, RigidlyRotatedBodyHasNoStress) {
  for (int dim : {2, 3}) {
    test::Body body = test::makeBody("sphere", 10, dim, LayoutKind::Gradational);
    const RestModel& m = *body.model;
    const Quat turn = dim == 3 ? Quat(Eigen::AngleAxisd(0.9, Vec3(1, 2, 3).normalized()))
                               : Quat(Eigen::AngleAxisd(0.9, Vec3::UnitZ()));
    std::vector<Vec3> x(m.numVertices());
    for (size_t i = 0; i < x.size(); ++i) x[i] = turn * m.restPositions[i] + Vec3(0.3, -0.2, dim == 3 ? 0.1 : 0);
    const std::vector<Quat> rest(m.numElements(), Quat::Identity());  // a cold-ish start: 0.9 rad away
    const std::vector<Real> s = elementVonMisesStress(m, x, rest);
    for (size_t e = 0; e < s.size(); ++e) ASSERT_LT(s[e], 1e-9 * m.material.youngsModulus) << "dim " << dim;
    // The same body stretched 1 % along its turned x axis is stressed: the test can fail.
    for (size_t i = 0; i < x.size(); ++i) {
      Vec3 r = m.restPositions[i];
      r.x() *= 1.01;
      x[i] = turn * r;
    }
    const std::vector<Real> t = elementVonMisesStress(m, x, rest);
    for (size_t e = 0; e < t.size(); ++e)
      ASSERT_NEAR(t[e], 0.01 * m.material.youngsModulus, 1e-6 * m.material.youngsModulus) << "dim " << dim;
  }
}

TEST(ElementStrain, TwoRegionsAreStressedInProportionToTheirModuli) {
  // The two halves of the section side by side (parallel): the same strain, stress E_r * strain.
  BarSpec bar;
  bar.across = 4, bar.along = 24, bar.width = 0.04, bar.layout = LayoutKind::Uniform;
  bar.split = BarSplit::Parallel;
  bar.material.youngsModulus = 1e6;
  RegionMaterial stiff;
  stiff.label = 2;
  stiff.youngsModulus = 4e6;
  bar.material.regions = {stiff};
  const Real strain = 1e-3;
  BuiltScene b = stretchedBar(bar, strain);
  const World& w = *b.world;
  const RestModel& m = w.model();
  const std::vector<Real> s = w.elementStress();
  Real sum[2] = {0, 0};
  int count[2] = {0, 0};
  for (size_t e : middleElements(m, bar.length())) {
    const int r = m.materialLabel[m.elementMaterial[e]] == 2 ? 1 : 0;
    EXPECT_DOUBLE_EQ(elementYoungsModulus(m, e), r ? 4e6 : 1e6);
    sum[r] += s[e], ++count[r];
  }
  ASSERT_GT(count[0], 2);
  ASSERT_GT(count[1], 2);
  const Real soft = sum[0] / count[0], hard = sum[1] / count[1];
  EXPECT_NEAR(soft, 1e6 * strain, 0.05 * 1e6 * strain);
  EXPECT_NEAR(hard, 4e6 * strain, 0.05 * 4e6 * strain);
  EXPECT_NEAR(hard / soft, 4.0, 0.2);
}

TEST(ElementStrain, PaperScalingUsesTheElementsEquivalentModulus) {
  MaterialSettings paper;
  paper.scaling = Scaling::Paper;
  test::Body body = test::makeBody("box", 4, 3, LayoutKind::Voxel, paper);
  const RestModel& m = *body.model;
  for (size_t e = 0; e < m.numElements(); ++e)
    EXPECT_DOUBLE_EQ(elementYoungsModulus(m, e), 2 * m.stiffness[e] / m.size[e]);
}

}  // namespace
}  // namespace gradel
