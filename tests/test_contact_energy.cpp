// Contacts never add energy (issue 15): a motionless obstacle held inside or against a damped
// body, with any restitution and friction, can only take energy out. The three reproductions of
// the issue (a sphere deep inside the body, a cylinder through it, a sphere pressing it into a
// wall) and a rapidcheck property over random bodies, obstacles and walls.
#include <gtest/gtest.h>
#include <rapidcheck/gtest.h>

#include <cstdlib>
#include <iomanip>
#include <sstream>

#include "gradel/contacts.h"
#include "test_support.h"

using namespace gradel;
using namespace gradel::test;

namespace {

ManipulatorSettings obstacle(ManipulatorShape shape, Real radius, const Vec3& at, Real e, Real mu) {
  ManipulatorSettings s;
  s.shape = shape;
  s.radius = radius;
  s.halfLength = 0.1;
  s.axis = Vec3(0, 0, 1);
  s.restitution = e;
  s.friction = mu;
  s.path.keys.push_back({0.0, at, std::nullopt});  // motionless
  return s;
}

// Total energy (kinetic + elastic + gravity) of a run: the value after the first step (which
// pushes the vertices out of the obstacle, legitimately storing elastic energy) and the largest
// value afterwards.
struct EnergyTrace {
  Real first = 0, max = 0, last = 0;
  Real ratio() const { return max / first; }
};

EnergyTrace trace(World& w, long steps, long every = 1) {
  EnergyTrace t;
  w.step();
  t.first = t.max = totalEnergy(w);
  for (long s = 1; s < steps; ++s) {
    w.step();
    if (s % every == 0 || s + 1 == steps) {
      const Real e = totalEnergy(w);
      t.max = std::max(t.max, e);
      t.last = e;
    }
  }
  return t;
}

struct Repro {
  Body body = makeBody("sphere", 12, 3, LayoutKind::Gradational);  // radius 6 cm, centre (6, 6, 6) cm
  SimulationSettings sim = [] {
    SimulationSettings s = isolated();
    s.damping = 2.0;
    return s;
  }();
  EnergyTrace run(const DomainSettings& d, std::vector<ManipulatorSettings> m) {
    World w(body.model, sim, d, std::move(m));
    return trace(w, long(0.6 / w.dt()));
  }
};

}  // namespace

// A vertex pressed against a motionless surface by its elastic force (at rest on it at the start
// of the step, pushed in by this step's acceleration) is put back without a bounce: reflecting
// the speed it gained inside would return every step energy the projection already paid for.
TEST(ContactEnergy, RestingContactDoesNotBounce) {
  Manipulator m;
  m.settings.radius = 1.0;
  m.settings.restitution = 1.0;
  const Real dt = 1e-3;
  const Vec3 xPrev(0, 1.0, 0);                       // on the surface
  const StepStart start{Vec3(0.2, 0, 0), dt, true};  // sliding, no normal speed; symplectic Euler
  Vec3 v(0.2, -0.03, 0);                             // a = -30 m/s^2 gained this step
  Vec3 x = xPrev + dt * v;
  resolveManipulator(m, xPrev, x, v, true, &start);
  EXPECT_GE(m.signedDistance(x, nullptr), 0.0);
  Vec3 n;
  m.signedDistance(x, &n);
  // No bounce (the old rule sent it back out at 0.03 m/s): its normal velocity at the time of
  // the positions, v + a dt / 2 (contacts.h), is 0; the stored (leapfrog) velocity is -a dt / 2.
  EXPECT_NEAR(v.dot(n) + 0.5 * dt * -30.0, 0.0, 1e-4);
  // The projection lifted it 3e-5 m against 30 m/s^2: that energy (9e-4 J/kg) comes out of the
  // sliding, 1/2 (0.2^2 - vx^2) = 9e-4.
  EXPECT_NEAR(v.x(), std::sqrt(0.04 - 2 * 9e-4), 1e-4);
}

// A real strike keeps the paper's elastic bounce: a vertex arriving at 2 m/s leaves at the speed
// it crossed the surface with (here no force: 2 m/s).
TEST(ContactEnergy, StrikeStillBouncesElastically) {
  Manipulator m;
  m.settings.radius = 1.0;
  m.settings.restitution = 1.0;
  const Real dt = 1e-3;
  const Vec3 xPrev(0, 1.001, 0);
  const StepStart start{Vec3(0, -2.0, 0), dt, true};
  Vec3 v(0, -2.0, 0), x = xPrev + dt * v;
  resolveManipulator(m, xPrev, x, v, true, &start);
  EXPECT_NEAR(v.y(), 2.0, 1e-12);
  // Pressed in by a force on the way (u0 = -2, u1 = -2.5, a = -500): it leaves at its approach
  // speed 2 m/s (never more), less the elastic energy the projection stored: |a| depth =
  // 500 * 0.0015 J/kg; that is its velocity at the time of the positions, v + a dt / 2.
  x = xPrev + dt * Vec3(0, -2.5, 0), v = Vec3(0, -2.5, 0);
  resolveManipulator(m, xPrev, x, v, true, &start);
  EXPECT_NEAR(v.y() + 0.5 * dt * -500.0, std::sqrt(4.0 - 2 * 500 * 0.0015), 1e-6);
  // Started inside (no crossing): put out, no bounce.
  const Vec3 inside(0, 0.99, 0);
  x = inside + dt * Vec3(0, -2.0, 0), v = Vec3(0, -2.0, 0);
  resolveManipulator(m, inside, x, v, true, &start);
  EXPECT_NEAR(v.y(), 0.0, 1e-12);
}

// The reproductions, at the default step. Before the crossing-speed rule: sphere held
// inside x1.00 (not reproduced in this setting), cylinder through the body x26, sphere pressing
// the body into a wall x13. After: x1.00, x34, x2.3. The cylinder and wall cases still gain
// energy even at restitution 0 (cylinder x5.4): the projection adds about twice the elastic
// energy that zeroing the normal speed removes; open (issue 15), hence disabled.
TEST(ContactEnergy, SphereHeldDeepInsideTakesEnergyOut) {
  Repro r;
  const EnergyTrace t = r.run({}, {obstacle(ManipulatorShape::Sphere, 0.024, Vec3(0.067, 0.058, 0.063), 1.0, 0.0)});
  std::printf("sphere inside: E after first step %.4g J, max %.4g J, ratio %.4f\n", t.first, t.max, t.ratio());
  EXPECT_LE(t.ratio(), 1.0 + 1e-9);
  EXPECT_LT(t.last, t.first);
}

TEST(ContactEnergy, CylinderThroughTheBodyTakesEnergyOut) {
  Repro r;
  const EnergyTrace t = r.run({}, {obstacle(ManipulatorShape::Cylinder, 0.02, Vec3(0.06, 0.06, 0.06), 1.0, 0.0)});
  std::printf("cylinder through: E after first step %.4g J, max %.4g J, ratio %.4f\n", t.first, t.max, t.ratio());
  EXPECT_LE(t.ratio(), 1.0 + 1e-9);
  EXPECT_LT(t.last, t.first);
}

TEST(ContactEnergy, SpherePressingIntoAWallTakesEnergyOut) {
  Repro r;
  DomainSettings d;
  d.enabled = true;
  d.min = Vec3(-1, -1, -1);
  d.max = Vec3(0.12, 1, 1);  // the body touches the +x wall; the sphere presses it 3 cm into it
  d.restitution = 1.0;
  const EnergyTrace t = r.run(d, {obstacle(ManipulatorShape::Sphere, 0.03, Vec3(0.03, 0.06, 0.06), 1.0, 0.0)});
  std::printf("sphere + wall: E after first step %.4g J, max %.4g J, ratio %.4f\n", t.first, t.max, t.ratio());
  EXPECT_LE(t.ratio(), 1.0 + 1e-9);
  EXPECT_LT(t.last, t.first);
}

// ---- property: random bodies, motionless obstacles and walls pressing them -------------------

namespace {

// Steps per case: 1e4 by default; GRADEL_PROPERTY_STEPS lowers it (the sanitizer pass).
long propertySteps() {
  const char* s = std::getenv("GRADEL_PROPERTY_STEPS");
  return s ? std::max(1L, std::atol(s)) : 10000L;
}

// Tolerance, relative to the larger of the reference and the elastic energy: the energy measured
// for symplectic Euler (v + a dt / 2, metrics()) is not its exactly conserved quantity; on a free
// body it stays flat to ~2e-5 over 1e5 steps. 1e-4 is above that measurement noise and far below
// the pumping seen (x2 to x1000).
const Real kTolerance = 1e-4;
const long kWindow = 20;

// The largest energy of a run over `steps` steps relative to the reference: the energy once the
// vertices placed inside an obstacle or beyond a wall are out (the deepest within 1 % of a
// voxel, at most 100 steps). Pushing them out legitimately stores elastic energy, and a vertex
// pinched between a wall and an obstacle (placed inside both) takes a few steps. The reference
// is the largest value over the next kWindow steps: a vertex pressed hard against a surface
// (a body crushed between two obstacles and a wall) moves in by a dt^2 and is put back every
// step, a step-to-step swing of the measured energy of order m (a dt)^2 that a single sample
// could catch at its low point.
struct Rise {
  long start = 0;
  Real e0 = 0, peak = 0, last = 0, elastic = 0;
  // Rounding: the energy is a sum over ~10^3 terms of size up to E, each with relative error
  // ~1e-16, and the symplectic energy measure itself (v + a dt / 2) has an O((omega dt)^2)
  // swing: kTolerance of the larger of E and the elastic energy scale is far above the first and
  // below any pumping (x2 to x1000).
  bool holds() const { return peak <= e0 + kTolerance * std::max(std::abs(e0), elastic) + 1e-12; }
};

Rise rise(World& w, long steps) {
  Rise r;
  do {
    w.step();
  } while (++r.start < 100 && w.metrics().maxPenetration > 1e-4);
  r.e0 = totalEnergy(w);
  for (long k = 1; k < kWindow; ++k) w.step(), r.e0 = std::max(r.e0, totalEnergy(w));
  r.peak = r.e0;
  for (long s = r.start + kWindow; s < steps; ++s) {
    w.step();
    if (s % 25 == 0) r.peak = std::max(r.peak, totalEnergy(w));
  }
  const Metrics m = w.metrics();
  r.last = m.totalEnergy();
  r.elastic = m.elasticEnergy;
  r.peak = std::max(r.peak, r.last);
  return r;
}

void energyNeverRises() {
  const std::string shape = *rc::gen::element<std::string>("sphere", "box");
  const int size = *rc::gen::inRange(6, 11);
  const Body body = makeBody(shape, size, 3, LayoutKind::Gradational);
  const Real h = 0.01 * size;  // body edge [m]; the body spans [0, h]^3
  SimulationSettings sim;
  sim.damping = *rc::gen::inRange(1, 51) * 0.1;  // (0, 5] 1/s
  sim.gravity =
      *rc::gen::element(0, 1) && !std::getenv("GRADEL_PROPERTY_NO_GRAVITY") ? Vec3(0, -9.81, 0) : Vec3::Zero();
  auto unit = [] { return *rc::gen::inRange(0, 101) * 0.01; };  // [0, 1]
  std::vector<ManipulatorSettings> obstacles;
  const int count = *rc::gen::inRange(1, 3);
  for (int i = 0; i < count; ++i) {
    const bool cylinder = *rc::gen::element(0, 1);
    // Centres anywhere in the body's box (some deep inside), radii 10-40 % of the edge.
    const Vec3 at(unit() * h, unit() * h, unit() * h);
    ManipulatorSettings m = obstacle(cylinder ? ManipulatorShape::Cylinder : ManipulatorShape::Sphere,
                                     (0.1 + 0.3 * unit()) * h, at, unit(), unit());
    m.halfLength = (0.2 + unit()) * h;
    m.axis = Vec3(unit() - 0.5, unit() - 0.5, unit() - 0.5 + 1e-3);
    obstacles.push_back(m);
  }
  DomainSettings walls;
  walls.enabled = *rc::gen::element(0, 1) && !std::getenv("GRADEL_PROPERTY_NO_WALLS");
  if (walls.enabled) {  // a floor and a side wall cutting up to 20 % into the body
    walls.min = Vec3(-1, unit() * 0.2 * h, -1);
    walls.max = Vec3(h * (1 - 0.2 * unit()), 1, 1);
    walls.restitution = unit();
    walls.friction = unit();
  }
  for (const ManipulatorSettings& o : obstacles)
    RC_LOG() << std::setprecision(17) << manipulatorShapeName(o.shape) << " at " << o.path.keys[0].position.transpose()
             << " r " << o.radius << " half " << o.halfLength << " axis " << o.axis.transpose() << " e "
             << o.restitution << " mu " << o.friction << "\n";
  if (walls.enabled)
    RC_LOG() << std::setprecision(17) << "walls min " << walls.min.transpose() << " max " << walls.max.transpose()
             << " e " << walls.restitution << " mu " << walls.friction << "\n";
  World w(body.model, sim, walls, obstacles);
  const Rise r = rise(w, propertySteps());
  RC_ASSERT(std::isfinite(r.peak));
  RC_LOG() << shape << " " << size << ", damping " << sim.damping << ", " << obstacles.size() << " obstacles, walls "
           << walls.enabled << ": E once out of the obstacles (step " << r.start << ") " << r.e0 << " J, peak "
           << r.peak << " J, now " << r.last << " J\n";
  RC_ASSERT(r.holds());
}

}  // namespace

// Random bodies (spheres and boxes, 6^3 to 10^3), one or two motionless spheres or capped
// cylinders anywhere in them (some deep inside, thin ones at the edges), maybe a floor and a side
// wall cutting into them, damping (0, 5] /s, gravity or none, any restitution and friction. The
// CI default is 6 cases of 1e4 steps from a fixed seed (a few seconds; deterministic); explore
// with RC_PARAMS="seed=..." and GRADEL_PROPERTY_CASES / GRADEL_PROPERTY_STEPS (GRADEL_PROPERTY_NO_WALLS,
// _NO_GRAVITY narrow it). Before the fixes of issue 15 it failed within 100 cases of 3000 steps
// (the two counterexamples below; 0.047 J -> 58 J and 0.90 J -> 29 J in the issue).
TEST(ContactEnergy, NeverRisesWithMotionlessObstaclesAndWalls) {
  rc::detail::TestParams params = rc::detail::configuration().testParams;
  params.maxSuccess = std::getenv("GRADEL_PROPERTY_CASES") ? std::atoi(std::getenv("GRADEL_PROPERTY_CASES")) : 6;
  if (!std::getenv("RC_PARAMS")) params.seed = 15;
  rc::detail::TestMetadata metadata;
  metadata.id = "ContactEnergy/NeverRisesWithMotionlessObstaclesAndWalls";
  const auto result = rc::detail::checkTestable(&energyNeverRises, metadata, params);
  if (!result.template is<rc::detail::SuccessResult>()) {
    std::ostringstream ss;
    rc::detail::printResultMessage(result, ss);
    FAIL() << ss.str();
  }
}

// The property's counterexamples, as regular tests (3000 steps each).

// A thin capped cylinder through the corner of a falling sphere (no walls, restitution and
// friction 0): a vertex on the cylinder's rim, pulled across it, was taken for one that passed
// through the middle (cap and side normals orthogonal, their dot product -1e-16) and put back
// every step (energy +0.3 %, and a frictionless rim holding a vertex); leaving the rim along the
// side it was taken for a pass-through (a corner clipped by 1e-8 m) and put back while its
// velocity grew: 0.040 J -> 4.3 J once the first was fixed alone.
TEST(ContactEnergy, CylinderRimNeitherHoldsNorPumpsAVertex) {
  const Body body = makeBody("sphere", 6, 3, LayoutKind::Gradational);
  SimulationSettings sim;
  sim.damping = 0.1;
  sim.gravity = Vec3(0, -9.81, 0);
  ManipulatorSettings m = obstacle(ManipulatorShape::Cylinder, 0.006, Vec3(0, 0, 0), 0, 0);
  m.halfLength = 0.0138;
  m.axis = Vec3(-0.5, -0.47, -0.499);
  World w(body.model, sim, {}, {m});
  const Rise r = rise(w, 3000);
  std::printf("cylinder rim: E %.4g J (step %ld), peak %.4g J, last %.4g J\n", r.e0, r.start, r.peak, r.last);
  EXPECT_TRUE(r.holds());
  EXPECT_LT(r.last, r.e0);
}

// A 7^3 box dropped onto two overlapping spheres sunk in the floor, near a side wall (weak
// damping, 0.3/s): the push out of the spheres leaves a corner vertex oscillating in the fastest
// element mode (8 steps a period, omega dt = 0.8) and hitting the floor (restitution 0.78) while
// its element pulls it up. Reflecting the leapfrog velocity added m |vn| a dt (1 + e) / 2 of
// measured energy per bounce: 1.2 J -> 290 J in 3000 steps. Reflecting the velocity at the time
// of the positions takes energy out.
TEST(ContactEnergy, FastModeBouncingOnTheFloorTakesEnergyOut) {
  const Body body = makeBody("box", 7, 3, LayoutKind::Gradational);
  SimulationSettings sim;
  sim.damping = 3 * 0.1;
  sim.gravity = Vec3(0, -9.81, 0);
  // The property's values to the last bit (the run is chaotic: rounded to 3 digits it stays calm).
  const Real h = 0.01 * 7;
  auto u = [](int k) { return k * 0.01; };
  const ManipulatorSettings a =
      obstacle(ManipulatorShape::Sphere, (0.1 + 0.3 * u(40)) * h, Vec3(u(65) * h, u(8) * h, u(44) * h), u(21), u(54));
  const ManipulatorSettings b =
      obstacle(ManipulatorShape::Sphere, (0.1 + 0.3 * u(20)) * h, Vec3(u(39) * h, u(4) * h, u(47) * h), u(27), u(92));
  DomainSettings d;
  d.enabled = true;
  d.min = Vec3(-1, u(35) * 0.2 * h, -1);
  d.max = Vec3(h * (1 - 0.2 * u(73)), 1, 1);
  d.restitution = u(78);
  d.friction = u(1);
  World w(body.model, sim, d, {a, b});
  const Rise r = rise(w, 3000);
  std::printf("fast mode on the floor: E %.4g J (step %ld), peak %.4g J, last %.4g J\n", r.e0, r.start, r.peak, r.last);
  EXPECT_TRUE(r.holds());
  EXPECT_LT(r.last, r.e0);
}

// The property's counterexample at the operator rule's 0.2 (seed 15): a 6^3 box pinched between
// a sphere, a thin cylinder and two walls (damping 0.9/s, gravity). Squeezed, its elements' tangent
// stiffness rises above the operator's at rest, and a mode at about 4 steps a period (omega dt
// ~1.6 where omega_max dt at rest is 1.26) grew from step ~630: 0.197 J -> 0.94 J. The same case
// holds up to 0.19 and breaks at 0.2; the default 0.175 (omega_max dt = 1.10) is below that.
TEST(ContactEnergy, PinchedBoxDoesNotPumpAtTheDefaultStep) {
  const Body body = makeBody("box", 6, 3, LayoutKind::Gradational);
  SimulationSettings sim;
  sim.damping = 0.9;
  sim.gravity = Vec3(0, -9.81, 0);
  ManipulatorSettings a = obstacle(ManipulatorShape::Sphere, 0.016439999999999996,
                                   Vec3(0.034799999999999998, 0.0138, 0.0084000000000000012), 0.47000000000000003, 0);
  a.halfLength = 0.012;
  ManipulatorSettings b = obstacle(ManipulatorShape::Cylinder, 0.0077999999999999996,
                                   Vec3(0.031199999999999999, 0.027, 0.0132), 0.070000000000000007, 0.11);
  b.halfLength = 0.012;
  b.axis = Vec3(-0.0099999999999999898, -0.27000000000000002, -0.018999999999999989);
  DomainSettings d;
  d.enabled = true;
  d.min = Vec3(-1, 0.00035999999999999997, -1);
  d.max = Vec3(0.057239999999999992, 1, 1);
  d.restitution = 0.59999999999999998;
  d.friction = 0.059999999999999998;
  World w(body.model, sim, d, {a, b});
  ASSERT_EQ(w.settings().dtPeriod, PeriodRule::Operator);
  const Rise r = rise(w, 3000);
  std::printf("pinched box: E %.4g J (step %ld), peak %.4g J, last %.4g J\n", r.e0, r.start, r.peak, r.last);
  EXPECT_TRUE(r.holds());
}
