// A 2D world stays in its plane z = 0 whatever its inputs' z (src/plane.h): the inputs are put
// into the plane where they enter (buildScene's normalizeFor2D, World's API), never inside a
// kernel or a step stage. Every entry point is given a non-zero z here, under each integrator;
// an entry point that forgot to project would leave a vertex, a velocity or a contact torque
// out of the plane.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "gradel/integrator.h"
#include "gradel/scene.h"
#include "gradel/shapes.h"
#include "gradel/world.h"
#include "test_support.h"

namespace gradel {
namespace {

// What a run saw: entries out of the plane (must stay 0) and whether the inputs acted at all.
struct PlaneCheck {
  size_t positionsOff = 0, velocitiesOff = 0, forcesOff = 0;
  Real zMomentumMax = 0;   ///< [kg m/s] max |sum m v_z| over the steps.
  Real manipulatorImpulse[2] = {0, 0};  ///< [N s] |force| dt summed: the manipulators touched.
  Real wallImpulse = 0;    ///< [N s] the floor touched.
};

void checkStep(const World& w, PlaneCheck& c) {
  const State& s = w.state();
  Real pz = 0;
  for (size_t i = 0; i < s.positions.size(); ++i) {
    c.positionsOff += s.positions[i].z() != 0;
    c.velocitiesOff += s.velocities[i].z() != 0;
    pz += w.model().mass[i] * s.velocities[i].z();
  }
  c.zMomentumMax = std::max(c.zMomentumMax, std::abs(pz));
  const ContactForces& f = w.stepContactForces();
  auto off = [](const ContactForce& cf) {
    return cf.force.z() != 0 || cf.torque.x() != 0 || cf.torque.y() != 0;
  };
  for (size_t k = 0; k < f.manipulators.size(); ++k) {
    c.forcesOff += off(f.manipulators[k]);
    if (k < 2) c.manipulatorImpulse[k] += f.manipulators[k].force.norm() * w.dt();
  }
  for (const ContactForce& cf : f.wall) c.forcesOff += off(cf);
  c.wallImpulse += f.walls.force.norm() * w.dt();
}

// The right-hand circle, moved from outside every step (setManipulatorPose) with z != 0.
void poseFromOutside(World& w, size_t k) {
  const Real t = w.time();
  w.setManipulatorPose(k, Vec3(0.105 - 0.3 * t, 0.04, 0.7), Vec3(-0.3, 0.1, 3.0));
}

void expectInPlane(const PlaneCheck& c, IntegratorKind kind) {
  EXPECT_EQ(c.positionsOff, 0u);
  EXPECT_EQ(c.velocitiesOff, 0u);
  EXPECT_EQ(c.forcesOff, 0u);
  EXPECT_EQ(c.zMomentumMax, 0.0);
  // The inputs acted: both circles pushed the body, and (explicit steps) the body swung onto the
  // floor. (The frame-size steps' ledger shows no floor impulse in these 12 steps.)
  EXPECT_GT(c.manipulatorImpulse[0], 0);
  EXPECT_GT(c.manipulatorImpulse[1], 0);
  if (kind == IntegratorKind::SymplecticEuler) EXPECT_GT(c.wallImpulse, 0);
}

SimulationSettings settingsFor(IntegratorKind kind) {
  SimulationSettings s = kind == IntegratorKind::SymplecticEuler ? test::isolated() : test::frameStep(kind);
  s.gravity = Vec3(0.5, -9.81, 4.0);  // z: projected by the World's constructor
  return s;
}

ManipulatorSettings leftCircle() {
  ManipulatorSettings m;
  m.shape = ManipulatorShape::Circle;
  m.radius = 0.02;
  m.path.keys = {{0.0, Vec3(-0.03, 0.04, 0.5), Vec3(0.3, 0, -1.0)}, {0.1, Vec3(0.0, 0.04, -0.2), Vec3(0.3, 0, 2.0)}};
  return m;
}

ManipulatorSettings rightCircle() {
  ManipulatorSettings m;
  m.shape = ManipulatorShape::Circle;
  m.radius = 0.02;
  return m;
}

PinSettings cornerPin() {  // the bottom-left corner (the body swings down onto the floor), its path with z != 0
  PinSettings p;
  p.min = Vec3(-0.001, -0.001, -1), p.max = Vec3(0.011, 0.011, 1);
  p.path.keys = {{0.0, Vec3(0, 0, 0.2), Vec3(0.05, 0, 1.0)}, {0.2, Vec3(0.01, 0, -0.3), std::nullopt}};
  return p;
}

DomainSettings floorBelow() {  // the floor 2 mm below the body; a z range off the plane: walls ignore z in 2D
  DomainSettings d;
  d.enabled = true;
  d.min = Vec3(-0.2, -0.002, 0.5), d.max = Vec3(0.3, 0.3, 0.6);
  return d;
}

Real endTime(IntegratorKind kind) { return kind == IntegratorKind::SymplecticEuler ? 0.1 : 0.2; }

// Steps to the end time, the right-hand circle posed from outside before every step.
PlaneCheck run(World& w, IntegratorKind kind) {
  PlaneCheck c;
  checkStep(w, c);
  while (w.time() < endTime(kind)) {
    poseFromOutside(w, 1);
    w.step();
    checkStep(w, c);
  }
  return c;
}

class Planar2D : public ::testing::TestWithParam<IntegratorKind> {};

// Through World's API: an origin, gravity, initial velocity, scripted and posed manipulators, a
// pin path and external forces, all with z != 0.
TEST_P(Planar2D, WorldApiKeepsEveryInputInThePlane) {
  const IntegratorKind kind = GetParam();
  const test::Body b = test::makeBody("box", 8, 2, LayoutKind::Gradational, {}, 0.01, Vec3(0, 0, 0.3));
  ASSERT_EQ(b.model->origin.z(), 0.0);  // buildRestModel: the body in the plane
  WorldSettings ws;
  ws.simulation = settingsFor(kind);
  ws.domain = floorBelow();
  ws.manipulators = {leftCircle(), rightCircle()};
  ws.pins = {cornerPin()};
  ws.bodyVelocities = {Vec3(0.05, 0, 2.0)};
  World w(b.model, ws, {});
  poseFromOutside(w, 1);
  std::vector<uint32_t> ids(b.model->numVertices());
  for (size_t i = 0; i < ids.size(); ++i) ids[i] = uint32_t(i);
  w.addExternalForces(ids, std::vector<Vec3>(ids.size(), Vec3(1e-4, 2e-4, 5.0)));
  expectInPlane(run(w, kind), kind);
  EXPECT_NE(w.externalImpulse().x(), 0);  // the forces acted, in the plane
  EXPECT_EQ(w.externalImpulse().z(), 0);
}

// Through a scene built in code (buildScene's normalizeFor2D): the body's position and velocity,
// gravity, the manipulators' and pins' paths with z != 0 and a domain whose z range is empty.
TEST_P(Planar2D, SceneIsNormalisedOnceInBuildScene) {
  const IntegratorKind kind = GetParam();
  Scene s;
  s.name = "plane";
  s.dim = 2;
  s.bodies[0].shape = presetShape("box", 8, 2, 0.01);
  s.bodies[0].position = Vec3(0, 0, 0.3);
  s.bodies[0].velocity = Vec3(0.05, 0, 2.0);
  s.simulation = settingsFor(kind);
  s.domain = floorBelow();
  s.domain.min.z() = s.domain.max.z() = 0.25;
  s.manipulators = {leftCircle(), rightCircle()};
  s.pins = {cornerPin()};
  s.pins[0].min.z() = s.pins[0].max.z() = 0.25;  // no vertex at z = 0.25: the plane's slab selects them
  BuiltScene built = buildScene(s);
  World& w = *built.world;
  EXPECT_EQ(w.model().origin.z(), 0.0);
  EXPECT_EQ(w.domain().min.z(), -1.0);
  EXPECT_EQ(w.domain().max.z(), 1.0);
  EXPECT_EQ(w.manipulators()[0].position.z(), 0.0);
  EXPECT_FALSE(w.pinned().empty());
  expectInPlane(run(w, kind), kind);
}

INSTANTIATE_TEST_SUITE_P(Integrators, Planar2D,
                         ::testing::Values(IntegratorKind::SymplecticEuler, IntegratorKind::Implicit,
                                           IntegratorKind::LargeStep),
                         [](const ::testing::TestParamInfo<IntegratorKind>& i) {
                           return std::string(integratorKindName(i.param));
                         });

}  // namespace
}  // namespace gradel
