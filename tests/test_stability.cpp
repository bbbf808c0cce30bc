// stability.h: the body's fastest vibration, the explicit step's limit.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <random>

#include "gradel/element.h"
#include "gradel/stability.h"
#include "test_support.h"

using namespace gradel;
using namespace gradel::test;

namespace {

// lambda_max of M^-1 K with K from central differences of element.h's forces at rest (the
// nonlinear kernel the explicit step uses, not element_stiffness.h): the dense reference.
double denseLambdaMax(const RestModel& m) {
  const int D = m.dim, V = int(m.numVertices()), N = D * V;
  const std::vector<Vec3> R0s = m.pairRestOffsets();
  Eigen::MatrixXd K(N, N);
  std::vector<Vec3> x = m.restPositions, f;
  auto forces = [&](std::vector<Vec3>& out) {
    out.assign(V, Vec3::Zero());
    std::vector<Vec3> fe;
    for (size_t e = 0; e < m.numElements(); ++e) {
      const uint32_t b = m.elemStart[e], n = m.elemStart[e + 1] - b;
      fe.assign(n, Vec3::Zero());
      Quat q = Quat::Identity();
      elementForces(D, x.data(), &m.elemVerts[b], &R0s[b], int(n), m.stiffness[e], q, fe.data(), 50);
      for (uint32_t k = 0; k < n; ++k) out[m.elemVerts[b + k]] += fe[k];
    }
  };
  const double eps = 1e-7 * m.voxelSize;
  std::vector<Vec3> fp, fm;
  for (int j = 0; j < N; ++j) {
    const int v = j / D, a = j % D;
    x[v][a] += eps, forces(fp);
    x[v][a] -= 2 * eps, forces(fm);
    x[v][a] += eps;
    for (int i = 0; i < N; ++i) K(i, j) = -(fp[i / D][i % D] - fm[i / D][i % D]) / (2 * eps);
  }
  Eigen::VectorXd s(N);
  for (int i = 0; i < N; ++i) s(i) = 1 / std::sqrt(m.mass[i / D]);
  const Eigen::MatrixXd A = s.asDiagonal() * (0.5 * (K + K.transpose())) * s.asDiagonal();
  return Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(A, Eigen::EigenvaluesOnly).eigenvalues().maxCoeff();
}

}  // namespace

TEST(Stability, highestFrequencyMatchesTheDenseEigenvalueOfSmallBodies) {
  struct Case {
    const char* shape;
    int size, dim;
  };
  for (const Case& c : {Case{"box", 4, 3}, Case{"sphere", 6, 3}, Case{"cylinder", 6, 3}, Case{"sphere", 10, 2}}) {
    SCOPED_TRACE(std::string(c.shape) + " " + std::to_string(c.size) + " dim " + std::to_string(c.dim));
    const Body b = makeBody(c.shape, c.size, c.dim, LayoutKind::Gradational);
    const double exact = std::sqrt(denseLambdaMax(*b.model));
    const FrequencyEstimate est = highestFrequency(*b.model);
    EXPECT_NEAR(est.ritz / exact, 1.0, 2e-3);     // Lanczos has converged
    EXPECT_GE(est.omega, exact * (1 - 1e-6));     // the estimate used is never below the truth
    EXPECT_LE(est.omega, est.gershgorin * (1 + 1e-12));
    EXPECT_LE(exact, est.gershgorin * (1 + 1e-6));  // the vertex rule bounds it from above
  }
}

TEST(Stability, highestFrequencyIsDeterministicAndBelowTheVertexBound) {
  const Body b = makeBody("sphere", 16, 3, LayoutKind::Gradational);
  const FrequencyEstimate a = highestFrequency(*b.model), c = highestFrequency(*b.model);
  EXPECT_EQ(a.omega, c.omega);
  EXPECT_NEAR(a.gershgorin, 2 * M_PI / b.model->smallestVertexPeriod, 1e-9 * a.gershgorin);
  EXPECT_LE(a.ritz, a.omega);
  EXPECT_GT(a.ritz, 0.85 * a.gershgorin);  // the bound is close on a uniform body...
  EXPECT_LT(a.ritz, a.gershgorin);         // ...but not the value
}

// The estimate is the explicit step's real limit: symplectic Euler holds at omega dt = 2 pi 0.3
// = 1.88 and blows up at 2 pi 0.34 = 2.14 (every mode starts excited by a random displacement).
TEST(Stability, symplecticEulerHoldsBelowTheMeasuredLimitAndDivergesAbove) {
  const Body b = makeBody("sphere", 10, 3, LayoutKind::Gradational);
  auto energyGrowth = [&](double fraction) {
    SimulationSettings s = isolated();
    s.dtPeriod = PeriodRule::Operator;
    s.dtFraction = fraction;
    World w(b.model, s, {}, {});
    EXPECT_NEAR(w.dt(), fraction * 2 * M_PI / w.stabilityEstimate().omega, 1e-15);
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(-1, 1);
    for (Vec3& x : w.state().positions) x += 1e-4 * b.model->voxelSize * Vec3(u(rng), u(rng), u(rng));
    w.step();
    const double e0 = w.metrics().elasticEnergy + w.metrics().kineticEnergy;
    double peak = e0;
    for (int i = 0; i < 400; ++i) {
      w.step();
      const Metrics m = w.metrics();
      peak = std::max(peak, double(m.elasticEnergy + m.kineticEnergy));
    }
    return peak / e0;
  };
  EXPECT_LT(energyGrowth(0.175), 3.0);  // the default: bounded (symplectic Euler's energy swings)
  EXPECT_LT(energyGrowth(0.2), 3.0);
  EXPECT_LT(energyGrowth(0.25), 3.0);
  EXPECT_LT(energyGrowth(0.30), 5.0);
  EXPECT_GT(energyGrowth(0.34), 1e6);
}

TEST(Stability, operatorRuleStepsAtItsDefaultFraction) {
  const Body b = makeBody("sphere", 8, 3, LayoutKind::Gradational);
  EXPECT_EQ(World(b.model, isolated(), {}, {}).settings().dtPeriod, PeriodRule::Operator);  // the default, 0.175
  World w(b.model, isolated(), {}, {});
  EXPECT_EQ(w.settings().dtFraction, 0.175);
  EXPECT_DOUBLE_EQ(w.dt(), 0.175 * 2 * M_PI / w.stabilityEstimate().omega);
  // 1.75x (and a little more: the operator's period is longer than the vertex bound's) the step
  // of the vertex rule at the paper's 0.1.
  EXPECT_GT(w.dt(), 1.75 * 0.1 * b.model->smallestVertexPeriod);
}
