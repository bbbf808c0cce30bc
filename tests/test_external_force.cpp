// External forces on vertices (external_force.h, World::addExternalForces): the same impulse
// F dt at the start of every step in every integrator, so a force F on a free body for a time T
// changes its momentum by F T; pinned vertices ignore it; the divergence guard counts its work.
#include <gtest/gtest.h>

#include "gradel/divergence.h"
#include "test_support.h"

using namespace gradel;
using namespace gradel::test;

namespace {

/// A free 6^3 sphere in zero gravity, a force on its vertices [0, n/2) summing to `total` [N].
World pushedSphere(IntegratorKind kind, const Vec3& total, Real dt = 0) {
  const Body b = makeBody("sphere", 6, 3, LayoutKind::Gradational);
  SimulationSettings s = isolated();
  s.integrator = kind;
  s.dt = dt;
  World w(b.model, s, DomainSettings{}, {});
  const uint32_t half = uint32_t(w.model().numVertices() / 2);
  std::vector<uint32_t> ids;
  std::vector<Vec3> f;
  for (uint32_t i = 0; i < half; ++i) ids.push_back(i), f.push_back(total / half);
  w.addExternalForces(ids, f);
  return w;
}

}  // namespace

TEST(ExternalForce, ForceTimesTimeIsTheMomentumChangeInEveryIntegrator) {
  const Vec3 F(0.3, -0.2, 0.1);  // [N]
  for (IntegratorKind kind : {IntegratorKind::SymplecticEuler, IntegratorKind::ForwardEuler, IntegratorKind::Implicit,
                              IntegratorKind::LargeStep}) {
    const bool frame = kind == IntegratorKind::Implicit || kind == IntegratorKind::LargeStep;
    // Forward Euler gains energy at every dt without damping (which would take momentum): a dt
    // small enough that 200 steps stay put.
    World w = pushedSphere(kind, F, frame ? 1.0 / 240 : kind == IntegratorKind::ForwardEuler ? 1e-6 : 0);
    ASSERT_EQ(momentum(w).norm(), 0.0);
    const int steps = frame ? 24 : 200;
    for (int i = 0; i < steps; ++i) w.step();
    const Real T = steps * w.dt();
    const Vec3 expected = F * T;
    SCOPED_TRACE(integratorKindName(kind));
    EXPECT_LT((momentum(w) - expected).norm(), 1e-9 * expected.norm() + 1e-12)
        << "momentum " << momentum(w).transpose() << ", F T " << expected.transpose();
    EXPECT_LT((w.externalImpulse() - expected).norm(), 1e-12 * expected.norm());
    EXPECT_GT(w.externalWork(), 0);
    // The body was pushed on one side only, yet it moved as a whole: the centre of mass
    // travelled 1/2 (F / M) T^2 (within the integrators' first-order start).
    Real M = 0;
    for (Real m : w.model().mass) M += m;
    const Real travel = 0.5 * F.norm() / M * T * T;
    const Vec3 c0 = [&] {
      Vec3 c = Vec3::Zero();
      for (size_t u = 0; u < w.model().numVertices(); ++u) c += w.model().mass[u] * w.model().restPositions[u];
      return Vec3(c / M);
    }();
    EXPECT_NEAR((centreOfMass(w) - c0).dot(F.normalized()), travel, 0.15 * travel);
  }
}

TEST(ExternalForce, ClearedForcesStopActing) {
  World w = pushedSphere(IntegratorKind::SymplecticEuler, Vec3(0, 1, 0));
  for (int i = 0; i < 10; ++i) w.step();
  const Vec3 p = momentum(w);
  w.clearExternalForces();
  EXPECT_TRUE(w.externalForces().empty());
  for (int i = 0; i < 10; ++i) w.step();
  EXPECT_LT((momentum(w) - p).norm(), 1e-12 * p.norm());
}

TEST(ExternalForce, PinnedVerticesIgnoreIt) {
  const Body b = makeBody("box", 6, 3, LayoutKind::Uniform);
  World w(b.model, isolated(), DomainSettings{}, {});
  PinSettings pin;
  pin.min = Vec3(-1, -1, -1);
  pin.max = Vec3(1, 0.005, 1);  // the bottom layer of vertices
  w.setPins({pin});
  ASSERT_FALSE(w.pinned().empty());
  std::vector<uint32_t> ids(w.pinned().vertices);
  w.addExternalForces(ids, std::vector<Vec3>(ids.size(), Vec3(0, 100, 0)));
  for (int i = 0; i < 50; ++i) w.step();
  for (uint32_t u : ids) EXPECT_EQ(w.state().positions[u], w.model().restPositions[u]);
  EXPECT_EQ(w.externalImpulse().norm(), 0.0);
  EXPECT_EQ(w.externalWork(), 0.0);
  for (size_t u = 0; u < w.model().numVertices(); ++u)  // nothing moved: the forces went nowhere
    EXPECT_LT((w.state().positions[u] - w.model().restPositions[u]).norm(), 1e-12) << u;
}

TEST(ExternalForce, BadInputIsRefused) {
  World w = pushedSphere(IntegratorKind::SymplecticEuler, Vec3::Zero());
  const uint32_t n = uint32_t(w.model().numVertices());
  EXPECT_THROW(w.addExternalForces({n}, {Vec3(1, 0, 0)}), InputError);
  EXPECT_THROW(w.addExternalForces({0}, {Vec3(NAN, 0, 0)}), InputError);
  EXPECT_THROW(w.addExternalForces({0, 1}, {Vec3(1, 0, 0)}), InputError);
}

// A strong push gives the body far more kinetic energy than the budget at t = 0 holds: the guard
// passes it when the external work is counted (suppliedWork) and would call it a divergence
// without.
TEST(ExternalForce, TheDivergenceGuardCountsItsWork) {
  World w = pushedSphere(IntegratorKind::SymplecticEuler, Vec3(20, 0, 0));
  DivergenceGuard guard(energyBudget(w, 1.0));
  for (int i = 0; i < 1000; ++i) w.step();
  const Metrics m = w.metrics();
  EXPECT_FALSE(guard.check(m, suppliedWork(w), "test")) << "KE " << m.kineticEnergy << ", work " << w.externalWork();
  World fresh = pushedSphere(IntegratorKind::SymplecticEuler, Vec3(20, 0, 0));
  DivergenceGuard blindAtStart(energyBudget(fresh, 1.0));
  for (int i = 0; i < 1000; ++i) fresh.step();
  EXPECT_TRUE(blindAtStart.check(fresh.metrics(), fresh.contactWork(), "test").has_value());
  EXPECT_GE(w.externalWork(), m.kineticEnergy * 0.99);
}
