// contacts: manipulators and walls (sec. 3.5): nothing ends inside, bounces are elastic by
// default, friction follows Coulomb, fast manipulators cannot tunnel.
#include <gtest/gtest.h>

#include <random>

#include "gradel/contacts.h"
#include "test_support.h"

using namespace gradel;
using namespace gradel::test;

namespace {
Manipulator sphereAt(const Vec3& c, Real r, Real e = 1.0, Real mu = 0.0) {
  Manipulator m;
  m.settings.shape = ManipulatorShape::Sphere;
  m.settings.radius = r;
  m.settings.restitution = e;
  m.settings.friction = mu;
  m.position = m.previousPosition = c;
  return m;
}
}  // namespace

TEST(Contacts, VertexInsideIsPushedOutAndBouncesElastically) {
  const Manipulator m = sphereAt(Vec3::Zero(), 1.0);
  Vec3 xPrev(0, 1.05, 0), x(0, 0.9, 0), v(0.3, -2.0, 0);
  const ContactResult r = resolveManipulator(m, xPrev, x, v);
  EXPECT_NEAR(r.depth, 0.1, 1e-12);
  EXPECT_GE(m.signedDistance(x, nullptr), 0.0);
  EXPECT_NEAR(x.y(), 1.0, 1e-8);
  EXPECT_NEAR(v.y(), 2.0, 1e-12);  // e = 1: normal velocity reversed
  EXPECT_NEAR(v.x(), 0.3, 1e-12);  // frictionless: tangential kept
}

TEST(Contacts, RestitutionAndFriction) {
  const Manipulator m = sphereAt(Vec3::Zero(), 1.0, 0.0, 0.1);
  Vec3 xPrev(0, 1.05, 0), x(0, 0.95, 0), v(1.0, -2.0, 0);
  resolveManipulator(m, xPrev, x, v);
  EXPECT_NEAR(v.y(), 0.0, 1e-12);        // e = 0: normal velocity removed
  EXPECT_NEAR(v.x(), 1.0 - 0.2, 1e-12);  // Coulomb: |dv_t| = mu * |dv_n| = 0.1 * 2
  const Manipulator sticky = sphereAt(Vec3::Zero(), 1.0, 0.0, 10.0);
  x = Vec3(0, 0.95, 0), v = Vec3(1.0, -2.0, 0);
  resolveManipulator(sticky, xPrev, x, v);
  EXPECT_NEAR(v.norm(), 0.0, 1e-12);  // friction stops sliding, never reverses it
}

TEST(Contacts, BounceIsInTheManipulatorsMovingFrame) {
  // A manipulator moving at +5 m/s hits a vertex at rest: the vertex leaves at 10 m/s (e = 1).
  Manipulator m = sphereAt(Vec3(0, 0, 0), 1.0);
  m.previousPosition = Vec3(-0.06, 0, 0);
  m.velocity = Vec3(5, 0, 0);
  Vec3 x(1.0 - 0.05, 0, 0), v(0, 0, 0);
  resolveManipulator(m, x, x, v);
  EXPECT_NEAR(v.x(), 10.0, 1e-9);
  EXPECT_GE(m.signedDistance(x, nullptr), 0.0);
}

TEST(Contacts, FastManipulatorCannotTunnel) {
  // In one step the sphere (r = 1) jumps from x = -3 to x = +3 past a vertex at the origin: the
  // vertex must end up in front of it, not behind.
  Manipulator m = sphereAt(Vec3(3, 0, 0), 1.0);
  m.previousPosition = Vec3(-3, 0, 0);
  m.velocity = Vec3(6 / 0.01, 0, 0);
  Vec3 x(0, 0.2, 0), v(0, 0, 0);
  resolveManipulator(m, x, x, v);
  EXPECT_GT(x.x(), 3.0);  // pushed ahead of the manipulator
  EXPECT_GE(m.signedDistance(x, nullptr), 0.0);
  EXPECT_GT(v.x(), 0.0);
}

TEST(Contacts, CylinderSignedDistance) {
  Manipulator m;
  m.settings.shape = ManipulatorShape::Cylinder;
  m.settings.radius = 1.0;
  m.settings.halfLength = 2.0;
  m.settings.axis = Vec3(0, 0, 1);
  Vec3 n;
  EXPECT_NEAR(m.signedDistance(Vec3(3, 0, 0), &n), 2.0, 1e-12);
  EXPECT_NEAR(n.x(), 1.0, 1e-12);
  EXPECT_NEAR(m.signedDistance(Vec3(0, 0, 2.5), &n), 0.5, 1e-12);
  EXPECT_NEAR(n.z(), 1.0, 1e-12);
  EXPECT_NEAR(m.signedDistance(Vec3(0.5, 0, 1.9), &n), -0.1, 1e-12);  // nearest the cap
  EXPECT_NEAR(n.z(), 1.0, 1e-12);
  EXPECT_NEAR(m.signedDistance(Vec3(0.9, 0, 0), &n), -0.1, 1e-12);  // nearest the side
  EXPECT_NEAR(m.signedDistance(Vec3(4, 0, 6), &n), 5.0, 1e-12);     // nearest the rim
}

TEST(Contacts, WallsKeepVerticesInsideAndReflect) {
  DomainSettings d;
  d.enabled = true;
  d.min = Vec3(0, 0, 0);
  d.max = Vec3(1, 1, 1);
  d.restitution = 0.5;
  Vec3 x(0.5, -0.1, 1.2), v(1, -2, 3);
  resolveDomain(d, x, x, v, 3);
  EXPECT_EQ(x, Vec3(0.5, 0, 1));
  EXPECT_NEAR(v.y(), 1.0, 1e-12);
  EXPECT_NEAR(v.z(), -1.5, 1e-12);
  EXPECT_NEAR(v.x(), 1.0, 1e-12);
}

TEST(Contacts, PathInterpolation) {
  Path p;
  p.keys.push_back({0.0, Vec3(0, 0, 0), std::nullopt});
  p.keys.push_back({1.0, Vec3(2, 0, 0), std::nullopt});
  p.keys.push_back({2.0, Vec3(2, 2, 0), Vec3(0, 1, 0)});
  p.keys.push_back({3.0, Vec3(2, 4, 0), Vec3(0, 3, 0)});
  EXPECT_EQ(p.position(-1), Vec3(0, 0, 0));
  EXPECT_TRUE(p.position(0.5).isApprox(Vec3(1, 0, 0)));
  EXPECT_TRUE(p.velocity(0.5).isApprox(Vec3(2, 0, 0)));
  EXPECT_TRUE(p.velocity(2.0).isApprox(Vec3(0, 1, 0)));  // Hermite segment starts at its key velocity
  // Velocity is the derivative of position on the Hermite segment.
  const Real t = 2.37, h = 1e-6;
  EXPECT_TRUE(((p.position(t + h) - p.position(t - h)) / (2 * h)).isApprox(p.velocity(t), 1e-6));
  // After the last key it keeps the last velocity.
  EXPECT_TRUE(p.position(4.0).isApprox(Vec3(2, 7, 0)));
}

namespace {
// Runs a world and checks after every step that no vertex is inside a manipulator or outside
// the box. Returns the world's final state for further checks.
void expectNoPenetration(World& w, int steps) {
  for (int s = 0; s < steps; ++s) {
    w.step();
    const auto& x = w.state().positions;
    for (size_t i = 0; i < x.size(); ++i) {
      for (const Manipulator& m : w.manipulators())
        ASSERT_GE(m.signedDistance(x[i], nullptr), -1e-12) << "vertex " << i << " inside at step " << s;
      if (w.domain().enabled)
        for (int a = 0; a < w.model().dim; ++a) {
          ASSERT_GE(x[i][a], w.domain().min[a]) << "vertex " << i << " outside at step " << s;
          ASSERT_LE(x[i][a], w.domain().max[a]) << "vertex " << i << " outside at step " << s;
        }
    }
  }
}
}  // namespace

TEST(Contacts, NoVertexInsideAfterAnyStepEvenWhenFast) {
  for (int dim : {2, 3}) {
    for (Real speed : {0.5, 20.0, 400.0}) {  // m/s; at 400 m/s it moves ~ its radius per step
      Body b = makeBody("sphere", 10, dim, LayoutKind::Gradational);
      DomainSettings d;
      d.enabled = true;
      d.min = Vec3(-0.2, -0.2, -0.2);
      d.max = Vec3(0.3, 0.3, 0.3);
      ManipulatorSettings ms;
      ms.shape = dim == 3 ? ManipulatorShape::Sphere : ManipulatorShape::Circle;
      ms.radius = 0.03;
      const Real t1 = 0.2 / speed;
      ms.path.keys.push_back({0.0, Vec3(-0.1, 0.05, dim == 3 ? 0.05 : 0), std::nullopt});
      ms.path.keys.push_back({t1, Vec3(0.1, 0.05, dim == 3 ? 0.05 : 0), std::nullopt});
      SimulationSettings s = isolated();
      World w(b.model, s, d, {ms});
      expectNoPenetration(w, 300);
      EXPECT_EQ(w.metrics().maxPenetration, 0.0);
    }
  }
}

TEST(Contacts, GraspAgainstWallKeepsEverythingOutside) {
  // A cylinder presses a sphere against the x = 0 wall: the vertices pinched between them never
  // leave the box and never end up in the cylinder.
  Body b = makeBody("sphere", 10, 3, LayoutKind::Gradational, {}, 0.01, Vec3(0.0, 0.0, 0.0));
  DomainSettings d;
  d.enabled = true;
  d.min = Vec3(0, -0.5, -0.5);
  d.max = Vec3(0.5, 0.5, 0.5);
  ManipulatorSettings ms;
  ms.shape = ManipulatorShape::Cylinder;
  ms.radius = 0.02;
  ms.halfLength = 0.1;
  ms.axis = Vec3(0, 0, 1);
  ms.path.keys.push_back({0.0, Vec3(0.14, 0.05, 0.05), std::nullopt});
  ms.path.keys.push_back({0.05, Vec3(0.09, 0.05, 0.05), std::nullopt});
  World w(b.model, isolated(), d, {ms});
  expectNoPenetration(w, int(0.08 / w.dt()));
  // The body is squeezed: the vertex that was rightmost at rest, under the cylinder, now sits
  // at the cylinder's surface (x <= 0.07) instead of 0.1.
  size_t tip = 0;
  for (size_t i = 0; i < b.model->numVertices(); ++i)
    if ((b.model->restPositions[i] - Vec3(0.1, 0.05, 0.05)).norm() <
        (b.model->restPositions[tip] - Vec3(0.1, 0.05, 0.05)).norm())
      tip = i;
  EXPECT_LT(w.state().positions[tip].x(), 0.075);  // it may slide a little along the (frictionless) cylinder
  EXPECT_GT(w.state().positions[tip].x(), 0.02);
}

TEST(Contacts, SlidingAlongACurvedSideIsNotMistakenForTunnelling) {
  // A vertex resting on a static cylinder's side slides along the axis and around it: the short
  // chord of its step dips inside the curved surface, which must not freeze it in place.
  Manipulator m;
  m.settings.shape = ManipulatorShape::Cylinder;
  m.settings.radius = 0.02;
  m.settings.halfLength = 0.08;
  m.settings.axis = Vec3(0, 1, 0);
  m.position = m.previousPosition = Vec3::Zero();
  const Vec3 start(0.02 * std::cos(0.3), 0.0, 0.02 * std::sin(0.3));
  Vec3 x = start + Vec3(0, -6e-4, 4e-4), v(0, -2.9, 2.0);  // a step of 0.7 mm along the side
  resolveManipulator(m, start, x, v);
  EXPECT_GT((x - start).norm(), 5e-4);  // it moved
  EXPECT_GE(m.signedDistance(x, nullptr), 0.0);
  EXPECT_NEAR(v.y(), -2.9, 1e-12);  // frictionless: tangential velocity untouched
}

TEST(Contacts, StaticFrictionHoldsPositionNotJustVelocity) {
  // A vertex pressed into a static sphere while being pulled sideways: with enough friction its
  // tangential step is undone (no creep); without friction it slides the full step.
  for (Real mu : {0.0, 2.0}) {
    const Manipulator m = sphereAt(Vec3::Zero(), 1.0, 0.0, mu);
    const Vec3 xPrev(0, 1.0 + 1e-9, 0);
    Vec3 x(0.001, 0.999, 0), v(0.1, -0.1, 0);  // 1 mm sideways, 1 mm in
    resolveManipulator(m, xPrev, x, v);
    EXPECT_GE(m.signedDistance(x, nullptr), 0.0);
    if (mu == 0) {
      EXPECT_NEAR(x.x(), 0.001, 1e-5);
    } else {
      EXPECT_NEAR(x.x(), 0.0, 1e-5);
      EXPECT_NEAR(v.norm(), 0.0, 1e-12);
    }
  }
}

// A manipulator added to a running world (the viewer's and Python's "add") appears where it is
// put, without sweeping in from the origin, and pushes the body out from its first step on; bad
// settings are input errors.
TEST(Contacts, ManipulatorAddedLaterActsFromWhereItIsPut) {
  Body b = makeBody("sphere", 10, 3, LayoutKind::Gradational);
  World w(b.model, isolated(), {}, {});
  for (int i = 0; i < 5; ++i) w.step();
  ManipulatorSettings ms;
  ms.radius = 0.02;
  const Vec3 at(0.05, 0.05, 0.10);  // pressed into the top of the ball (centre 0.05, radius 0.05)
  const size_t i = w.addManipulator(ms, at);
  EXPECT_EQ(i, 0u);
  EXPECT_EQ(w.manipulators()[i].position, at);
  EXPECT_EQ(w.manipulators()[i].previousPosition, at);
  Real inside = 0;
  for (const Vec3& x : w.state().positions) inside = std::max(inside, -w.manipulators()[i].signedDistance(x, nullptr));
  ASSERT_GT(inside, 0.005);  // vertices start inside it
  w.step();
  EXPECT_EQ(w.metrics().maxPenetration, 0.0);
  ms.radius = 0;
  EXPECT_THROW(w.addManipulator(ms), InputError);
  ms.radius = 0.01, ms.shape = ManipulatorShape::Cylinder, ms.axis = Vec3::Zero();
  EXPECT_THROW(w.addManipulator(ms), InputError);
  EXPECT_EQ(w.manipulators().size(), 1u);
}
