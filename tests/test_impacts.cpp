// Impacts between soft bodies (issue 26, item 1): body-body contact never invents energy. Two
// bodies thrown at each other (head on and glancing, equal and unequal, 4 to 20 m/s closing speed,
// no gravity, no damping) keep kinetic + elastic energy at or below what they started with (to a
// small numerical allowance), linear momentum to 1e-9 of its scale, a finite state, and no
// inverted element once they have parted; at the default step and at a step 2.5x larger.
#include <gtest/gtest.h>
#include <rapidcheck/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "gradel/bodies.h"
#include "gradel/body_contacts.h"
#include "gradel/scene.h"
#include "struck_balls_scene.h"
#include "test_support.h"

namespace gradel {
namespace {

// One impact: body A (at the origin) moving +x, body B beyond it moving -x, B's centre offset
// sideways (y) by `offset` times the sum of the two radii (0: head on).
struct Impact {
  std::string shapeA = "sphere", shapeB = "sphere";
  int sizeA = 16, sizeB = 16;  // voxels across
  Real youngA = 1e5, youngB = 1e5;
  Real poisson = 0;            // both bodies' Poisson's ratio
  Real voxel = 0.005;          // [m]
  Real closing = 4;            // [m/s] closing speed
  Real shareA = 0.5;           // A's part of it (1: B at rest)
  Real offset = 0;             // [-] sideways offset (glancing)
  Real gap = 0.5;              // [voxels] between the bodies at the start
  Real restitution = 0.5, friction = 0;
  Real dtFraction = 0.1;       // of the stiffest vertex's period (PeriodRule::Vertex)
  IntegratorKind integrator = IntegratorKind::SymplecticEuler;
  Real duration = 0;           // [s] 0: until parted (and at most maxDuration)
  Real maxDuration = 0.25;     // [s]
};

struct ImpactResult {
  Real e0 = 0;             // [J] kinetic + elastic at the start
  Real peak = 0;           // [-] the largest energy over e0
  Real end = 0;            // [-] energy at the end over e0
  Real momentum = 0;       // [-] largest |p - p0| over the momentum scale (sum m |v| at the start)
  Real minDet = 1;         // min element determinant at the end
  bool finite = true;
  bool touched = false;    // the bodies met
  bool parted = false;     // and were apart (no contact) at the end
  int steps = 0, takeBacks = 0;
  Real time = 0, dt = 0;
};

struct ImpactWorld {
  std::vector<test::Body> parts;
  std::unique_ptr<World> world;
  explicit ImpactWorld(const Impact& c) {
    MaterialSettings ma, mb;
    ma.youngsModulus = c.youngA, mb.youngsModulus = c.youngB;
    ma.poissonRatio = mb.poissonRatio = c.poisson;
    const Real rA = 0.5 * c.sizeA * c.voxel, rB = 0.5 * c.sizeB * c.voxel;
    const Vec3 originB(c.sizeA * c.voxel + c.gap * c.voxel, rA - rB + c.offset * (rA + rB), rA - rB);
    parts.push_back(test::makeBody(c.shapeA, c.sizeA, 3, LayoutKind::Gradational, ma, c.voxel));
    parts.push_back(test::makeBody(c.shapeB, c.sizeB, 3, LayoutKind::Gradational, mb, c.voxel, originB));
    SimulationSettings sim = test::isolated();
    sim.threads = 1;
    sim.integrator = c.integrator;
    sim.dtFraction = c.dtFraction;
    sim.dtPeriod = PeriodRule::Vertex;
    const Vec3 vA(c.shareA * c.closing, 0, 0), vB(-(1 - c.shareA) * c.closing, 0, 0);
    world = test::worldOfBodies(parts, {vA, vB}, sim, {c.restitution, c.friction, false});
  }
  Vec3 momentum() const { return test::momentum(*world); }
  Real momentumScale() const { return test::momentumScale(*world); }
};

Real energyOf(const Metrics& m) { return m.kineticEnergy + m.elasticEnergy; }

// Runs an impact: until `duration`, or (0) until the bodies have been apart for a while after
// they met (at most maxDuration). `trace` prints the energy every `trace` steps.
ImpactResult runWorld(World& world, const Impact& c, int trace);

ImpactResult runImpact(const Impact& c, int trace = 0) {
  ImpactWorld w(c);
  return runWorld(*w.world, c, trace);
}

// The loop of runImpact on a built world (a scene's: runSoakPair below); c gives the durations.
ImpactResult runWorld(World& world, const Impact& c, int trace) {
  ImpactResult r;
  r.dt = world.dt();
  r.e0 = energyOf(world.metrics());
  const Vec3 p0 = test::momentum(world);
  const Real scale = test::momentumScale(world);
  int apartSteps = 0;
  const int apartNeeded = std::max(50, int(0.01 / world.dt()));  // 10 ms apart
  for (;;) {
    world.step();
    ++r.steps;
    const BodyContactStats& st = world.bodyContactStats();
    r.takeBacks += st.takeBacks > 0;
    const Metrics m = world.metrics();
    const Real e = energyOf(m);
    if (!std::isfinite(e) || !std::isfinite(test::momentum(world).norm())) {
      r.finite = false;
      break;
    }
    r.peak = std::max(r.peak, e / r.e0);
    r.momentum = std::max(r.momentum, (test::momentum(world) - p0).norm() / scale);
    if (trace && r.steps % trace == 0)
      std::printf("  t %.5f E/E0 %.5f contacts %zu depth %.2e takeBacks %d to %.4f minDet %.3f stage %+.2e removed %.2e\n",
                  world.time(), e / r.e0, st.contacts, st.maxDepth, st.takeBacks, st.takenBackTo, m.minElementDet,
                  st.energyExcess / r.e0, st.energyRemoved / r.e0);
    if (trace && std::getenv("GRADEL_IMPACT_DEEP")) {  // the findings deeper than this [m], each step
      const Real deep = std::atof(std::getenv("GRADEL_IMPACT_DEEP"));
      const Vec3* x = world.state().positions.data();
      for (const BodyContacts::Contact& k : world.bodyContacts()->contacts())
        if (k.depth > deep) {
          const Vec3 p = k.w[0] * x[k.face[0]] + k.w[1] * x[k.face[1]] + k.w[2] * x[k.face[2]];
          std::printf("    deep: vertex %u face %u %u %u depth %.3e n (%.3f %.3f %.3f) gap now %.3e\n", k.vertex,
                      k.face[0], k.face[1], k.face[2], k.depth, k.n.x(), k.n.y(), k.n.z(), k.n.dot(x[k.vertex] - p));
        }
      std::printf("    kinetic %.6e elastic %.6e\n", m.kineticEnergy, m.elasticEnergy);
    }
    if (st.contacts > 0) r.touched = true, apartSteps = 0;
    else if (r.touched) ++apartSteps;
    if (c.duration > 0 ? world.time() >= c.duration
                       : (apartSteps >= apartNeeded || world.time() >= c.maxDuration))
      break;
    if (e > 1e3 * r.e0) break;  // diverged: no need to go on
  }
  const Metrics m = world.metrics();
  r.end = energyOf(m) / r.e0;
  r.minDet = m.minElementDet;
  r.parted = r.touched && apartSteps > 0;
  r.time = world.time();
  return r;
}

std::string describe(const ImpactResult& r) {
  char b[400];
  std::snprintf(b, sizeof b,
                "E0 %.4g J, peak %.4fx, end %.4fx, momentum %.2e, minDet %.3f, finite %d, touched %d, parted %d, "
                "steps %d (dt %.3g s, t %.4f s), steps taken back %d",
                r.e0, r.peak, r.end, r.momentum, r.minDet, int(r.finite), int(r.touched), int(r.parted), r.steps, r.dt,
                r.time, r.takeBacks);
  return b;
}

// The checks of an impact: energy never above its start (beyond `allowance`), momentum to 1e-9,
// finite, and the bodies met, parted and have every element upright.
void expectSafe(const Impact& c, Real allowance, const char* what) {
  const ImpactResult r = runImpact(c);
  SCOPED_TRACE(std::string(what) + ": " + describe(r));
  std::printf("  %s: %s\n", what, describe(r).c_str());
  EXPECT_TRUE(r.finite);
  EXPECT_TRUE(r.touched);
  EXPECT_LE(r.peak, 1 + allowance) << "energy over its start";
  EXPECT_LE(r.momentum, 1e-9);
  EXPECT_TRUE(r.parted) << "the bodies parted";
  EXPECT_GT(r.minDet, 0) << "an element inverted after they parted";
}

// The issue's scene: two 16^3 balls (5 mm voxels, E = 1e5 Pa) head on at 4 m/s (10 and 20 m/s: below), at the
// default step (dt_fraction 0.1 of the vertex period) and at 2.5x it (0.25). Before the fix the
// energy rose x1e5 at 4 m/s and the run diverged. 10 m/s (measured 2026-11-27): peak 1.0000x and
// 0.9951x, momentum 2e-14, min det 0.64 once parted, 2 and 9 steps taken back; before every
// finding deeper than kTakeBackDepth was asked of the winding number the last resort took the
// balls back in 688 of 776 steps and an element ended inverted (this file's earlier note).
class HeadOn : public ::testing::TestWithParam<std::tuple<Real, Real>> {};
TEST_P(HeadOn, NeverInventsEnergy) {
  Impact c;
  c.closing = std::get<0>(GetParam());
  c.dtFraction = std::get<1>(GetParam());
  expectSafe(c, 0.02, "head on");
}
INSTANTIATE_TEST_SUITE_P(Impacts, HeadOn, ::testing::Combine(::testing::Values(4.0), ::testing::Values(0.1, 0.25)));

// 10 m/s, both steps, both flavours (measured 2026-11-27, generic build: peak 1.0000x and 0.9951x,
// momentum 2e-14, min det 0.62 / 0.73 once parted, 23 and 125 steps taken back). Before the last
// resort stopped at its least fraction where every deep vertex was already about as deep at the
// step's start, the generic build (no FMA: the sanitizer pass) froze the pair at dt_fraction 0.1:
// 2,234 of 2,424 steps taken back to the same start, never parted.
class HeadOnFast : public ::testing::TestWithParam<std::tuple<Real, Real>> {};
TEST_P(HeadOnFast, NeverInventsEnergy) {
  Impact c;
  c.closing = std::get<0>(GetParam());
  c.dtFraction = std::get<1>(GetParam());
  expectSafe(c, 0.02, "head on");
}
INSTANTIATE_TEST_SUITE_P(Impacts, HeadOnFast, ::testing::Combine(::testing::Values(10.0), ::testing::Values(0.1, 0.25)));

// Not met yet (issue 26; disabled): at 20 m/s, twice the balls' wave speed sqrt(E / rho), the
// energy holds (2026-11-29, x86-64-v3, an earlier variant of addContacts: peak 1.0000x / 0.9949x at dt_fraction 0.1 / 0.25) but
// elements invert within 1.5 ms of the touch (min det -1.0 / -1.5 at 0.25 s) and the pair has not
// parted by then (260 / 957 steps taken back); both runs now end (65 s together) where before they
// did not within minutes. The property below runs them all.
class HeadOnFaster : public ::testing::TestWithParam<std::tuple<Real, Real>> {};
TEST_P(HeadOnFaster, DISABLED_NeverInventsEnergy) {
  Impact c;
  c.closing = std::get<0>(GetParam());
  c.dtFraction = std::get<1>(GetParam());
  expectSafe(c, 0.02, "head on");
}
INSTANTIATE_TEST_SUITE_P(Impacts, HeadOnFaster, ::testing::Combine(::testing::Values(20.0), ::testing::Values(0.1, 0.25)));

// A stiff box (E = 1e7) thrown at a soft ball at rest (E = 1e4), and a glancing hit of two balls
// (offset half the sum of the radii, with friction). Not met yet (issue 26; disabled): 2026-11-30,
// with the stage's energy cap (body_contact_energy.h), 1.27x at the default step (97x without it),
// not parted after 0.25 s, min det -0.68; 1.0000x at 2.5x the step, not parted. Earlier, measured
// 2026-11-29 (x86-64-v3, with an earlier variant of addContacts: docs/speed.md): at the default step the 14^3 ball's elements invert under the box
// (8 m/s into E = 1e4 Pa, min det -0.10) and the energy peaks at 1.31x; at 2.5x the step it holds
// (1.0000x, parted after 0.19 s). Before misread folds were kept (BodyContacts::addContacts)
// neither run ended within 2.5 minutes.
TEST(Impacts, DISABLED_StiffBoxIntoSoftBallAtRest) {
  for (const Real f : {0.1, 0.25}) {
    Impact c;
    c.shapeA = "box", c.sizeA = 10, c.youngA = 1e7;
    c.sizeB = 14, c.youngB = 1e4;
    c.closing = 8, c.shareA = 1, c.dtFraction = f;
    expectSafe(c, 0.02, f == 0.1 ? "box into ball, default dt" : "box into ball, 2.5x dt");
  }
}

// Measured 2026-11-29 (x86-64-v3): peak 1.0000x at both steps, parted, min det 0.81 / 0.68.
TEST(Impacts, GlancingHitWithFriction) {
  for (const Real f : {0.1, 0.25}) {
    Impact c;
    c.sizeA = c.sizeB = 12, c.closing = 10, c.offset = 0.5, c.friction = 0.5, c.restitution = 1, c.dtFraction = f;
    expectSafe(c, 0.02, f == 0.1 ? "glancing, default dt" : "glancing, 2.5x dt");
  }
}

// A sphere tool crossing at 12 m/s glances a 16^3 ball and pushes it into a 14^3 one
// (MultiBodyScene's scene with the tool 2x faster). Before misread folds were kept
// (BodyContacts::addContacts, issue 26): from about step 84 the struck ball's surface was crushed,
// vertices inside at a step's start were pushed out along far faces, each round's search radius
// grew with those corrections (0.036 -> 0.99 m over one step's rounds) and the next round found
// deeper "contacts" still: findings 0.68 m deep, 21 M nearest-point tests in the worst of the
// first 100 steps. Now (2026-11-29, x86-64-v3): 52,271 tests at most, the deepest 0.031 m, 74 ms.
TEST(Impacts, ViolentToolHitKeepsTheContactSearchBounded) {
  Scene s = parseScene(test::struckBallsScene(0.05), "violent.json");
  s.simulation.threads = 1;
  BuiltScene b = buildScene(s);
  World& world = *b.world;
  size_t mostTests = 0;
  Real deepest = 0;
  int touching = 0;
  for (int k = 0; k < 100; ++k) {
    world.step();
    const BodyContactStats& st = world.bodyContactStats();
    mostTests = std::max(mostTests, st.faceTests);
    deepest = std::max(deepest, st.maxDepth);
    touching += st.contacts > 0;
    const Metrics m = world.metrics();
    ASSERT_TRUE(std::isfinite(m.kineticEnergy + m.elasticEnergy)) << "step " << k;
  }
  std::printf("  most nearest-point tests in a step %zu, deepest finding %.4f m, %d steps in contact\n", mostTests,
              deepest, touching);
  EXPECT_GE(touching, 10);  // the balls met
  // A finding is no deeper than the step's own motion allows plus a voxel (the larger one: 12 mm):
  // both balls and the tool move at most ~3 voxels a step here.
  EXPECT_LE(deepest, 0.1);
  EXPECT_LE(mostTests, size_t(1500000));  // the narrow phase's work in a step (was 21 M)
}

// A stiff ball (9^3, E = 1.9e5 Pa) at 1.45 m/s into a soft one (6^3, E = 1.4e4 Pa) at rest,
// slightly off centre (found by scripts/soak). The soft ball's surface folds where it is crushed
// (elements at 40 % of their volume), and the pseudo-normal test read vertices of the stiff ball
// near the fold as up to 1.2 voxels inside although they had moved 0.02 voxel and the winding
// number of the soft surface says outside: pushed out along far faces, they took the energy to
// 1.8x in one step at 22.7 ms and to 28x (elements inverted) by 25 ms. Such findings are dropped
// (BodyContacts::dropUnreachable). Checked over the first 40 ms, the press and the first rebound.
// (Later, at 43 ms, this pair still ends stuck: a step ends with vertices inside that the
// incremental rounds did not find, and the last resort, which takes the bodies back to where the
// step started, cannot undo what was already inside then: issue 26's notes.)
TEST(Impacts, FoldedSoftSurfaceIsNotReadAsInside) {
  Impact c;
  c.sizeA = 9, c.youngA = 1.9e5;
  c.sizeB = 6, c.youngB = 1.37e4;
  c.voxel = 0.01, c.gap = 1;
  c.closing = 1.45, c.shareA = 1;
  c.offset = -0.168;
  c.restitution = 0.8, c.friction = 0.27;
  c.duration = 0.04;
  ImpactWorld w(c);
  World& world = *w.world;
  const Real e0 = energyOf(world.metrics());
  const Vec3 p0 = w.momentum();
  Real peak = 0, minDet = 1;
  size_t dropped = 0, contacts = 0;
  while (world.time() < c.duration) {
    world.step();
    const Metrics m = world.metrics();
    peak = std::max(peak, energyOf(m) / e0);
    minDet = std::min(minDet, m.minElementDet);
    dropped += world.bodyContactStats().unreachable;
    contacts += world.bodyContactStats().contacts;
  }
  std::printf("  peak %.4f E0, min det %.3f, contacts %zu, unreachable findings dropped %zu\n", peak, minDet, contacts,
              dropped);
  EXPECT_GT(contacts, 0u) << "the balls met";
  EXPECT_GT(dropped, 0u) << "the fold misled the pseudo-normal test (the case this covers)";
  EXPECT_LE(peak, 1.02) << "energy over its start";
  EXPECT_GT(minDet, 0) << "an element inverted";
  EXPECT_LE((w.momentum() - p0).norm(), 1e-9 * w.momentumScale());
}

// Pairs scripts/soak found (seed 3, `--kinds impacts`, 2026-11-27), as `gradel run` runs them:
// the soak's scene (1 cm voxels, a gap of one voxel, dt "auto", no gravity or damping) read and
// built as the CLI does, run for the soak's duration (the gap's time + 0.15 s).
ImpactResult runSoakPair(const char* shapeA, int sizeA, Real youngA, const char* shapeB, int sizeB, Real youngB,
                         Real closing, Real shareA, Real offset, Real restitution, Real friction) {
  const Real ra = 0.005 * sizeA, rb = 0.005 * sizeB, gap = 0.01;
  char text[1400];
  std::snprintf(text, sizeof text,
                R"({"dim": 3, "bodies": [
  {"name": "a", "shape": "%s", "size": %d, "voxel_size": 0.01, "material": {"youngs_modulus": %.17g, "density": 1000},
   "position": [%.17g, %.17g, %.17g], "velocity": [%.17g, 0, 0]},
  {"name": "b", "shape": "%s", "size": %d, "voxel_size": 0.01, "material": {"youngs_modulus": %.17g, "density": 1000},
   "position": [%.17g, %.17g, %.17g], "velocity": [%.17g, 0, 0]}],
 "simulation": {"dt": "auto", "damping": 0, "gravity": [0, 0, 0]},
 "body_contact": {"restitution": %.17g, "friction": %.17g}})",
                shapeA, sizeA, youngA, -gap / 2 - 2 * ra, -ra, -ra, closing * shareA, shapeB, sizeB, youngB, gap / 2,
                -rb + offset, -rb, -closing * (1 - shareA), restitution, friction);
  Scene scene = parseScene(text, "soak pair");
  scene.simulation.threads = 1;
  BuiltScene built = buildScene(scene);
  Impact c;
  c.duration = gap / closing + 0.15;
  return runWorld(*built.world, c, 0);
}

// A soak pair's checks: finite, met, energy at most `peak` times its start, momentum to 1e-9,
// every element upright at the end.
void expectSoakSafe(const ImpactResult& r, Real peak) {
  std::printf("  %s\n", describe(r).c_str());
  EXPECT_TRUE(r.finite);
  EXPECT_TRUE(r.touched);
  EXPECT_LE(r.peak, peak) << describe(r);
  EXPECT_LE(r.momentum, 1e-9) << describe(r);
  EXPECT_GT(r.minDet, 0) << describe(r);
}

// The two box pairs are met since misread folds are pushed out only past their start depth
// (BodyContacts::addContacts, 2026-11-29, x86-64-v3: peak 1.0000x, every element upright, parted,
// 0 steps taken back); the stiff ball into the soft one since the stage's energy cap
// (body_contact_energy.h, 2026-11-30: peak 1.0000x, end 0.994x; 1.034x before it). Before, measured
// 2026-11-27 through this harness's loop (energy every step) on the library:
// - a stiff 6^3 ball (E = 8.4e5 Pa) at 1.45 m/s into a soft one (E = 1.7e4 Pa) at rest: x1.22 here
//   (parameters rounded to 8 digits); the soak's own scene file: x319, min det -365 (`gradel run`:
//   exit 3 at 0.094 s): the pair is that sensitive. The soft ball folds, and the pseudo-normal test
//   reads vertices of the stiff one 0.5-1.2 voxels inside where the winding number says outside at
//   the step's start and end; dropUnreachable lets them through once a correction has moved one
//   vertex of the soft ball far (moved_ counts every correction of the stage), and pushed out along
//   far faces they pump. Bounding the reach by the step's own motion (movedStart_) gave x2.15, every
//   element upright, but froze Impacts/HeadOnFast at dt_fraction 0.25 (reverted, 9308ac4);
// - a soft 11^3 box (E = 1.3e4 Pa) at 3.54 m/s into a stiff one at rest, glancing: slow, not stuck
//   (`gradel run` did not end in 4 minutes): taken back to the step's start in every step, the warm
//   start applies again every contact it kept, which then never moves: 18,000 contacts a step by
//   step 66 and growing. With movedStart_: 610 steps, energy at most its start, min det -0.1 at the end;
// - a soft 7^3 box (E = 2.4e4 Pa) at 3.96 m/s into a softer 8^3 ball at rest: dt "auto" 1.1 ms,
//   0.44 voxel of closing a step; the last resort keeps 1/16 of the step in 123 of 139 steps while
//   the ball's elements invert (min det -30) and pump: x2.40 (before it kept 1/16: 1.000x, min det
//   -0.19 at the end). Neither an inelastic impulse at the kept deep contacts (x2.48) nor pushing
//   them out only by what they gained in the step (x1.79) holds it.
TEST(Impacts, SoakStiffBallIntoSoftBall) {
  expectSoakSafe(runSoakPair("sphere", 6, 841179.66, "sphere", 6, 17011.986, 1.4462628, 1, -0.0029662380, 0.38221466,
                             0.65950389),
                 1.02);
}

TEST(Impacts, SoakSoftBoxIntoStiffBox) {
  expectSoakSafe(runSoakPair("box", 11, 455601.63, "box", 11, 13435.029, 3.5369669, 0, -0.015810840, 0.65772783,
                             0.77752244),
                 1.02);
}

TEST(Impacts, SoakSoftBoxIntoSofterBall) {
  expectSoakSafe(runSoakPair("box", 7, 23719.777, "sphere", 8, 10575.618, 3.9602686, 1, 0.012325125, 0.26609805,
                             0.19837221),
                 1.02);
}

// The stage's energy cap (body_contact_energy.h) takes an excess out of the touched vertices'
// motion about their mean per group of bodies in contact: two pairs hitting at once, far apart,
// keep each its own momentum (one mean over both bodies of both pairs moved 7.8e-3 kg m/s, a
// third of a pair's momentum, from one pair to the other), and the cap acted (the stiff-into-soft pair at 1 m/s, restitution 0: the case the cap
// was made for, 1.033x before it).
TEST(Impacts, EnergyCapKeepsEachPairsMomentum) {
  MaterialSettings stiff, soft;
  stiff.youngsModulus = 39810.7, soft.youngsModulus = 1e4;
  const Real h = 0.005;
  std::vector<test::Body> parts;
  parts.push_back(test::makeBody("sphere", 7, 3, LayoutKind::Gradational, stiff, h));
  parts.push_back(test::makeBody("sphere", 6, 3, LayoutKind::Gradational, soft, h, Vec3(7.5 * h, 0.5 * h, 0.5 * h)));
  parts.push_back(test::makeBody("sphere", 7, 3, LayoutKind::Gradational, stiff, h, Vec3(0, 0, 0.2)));
  parts.push_back(test::makeBody("sphere", 6, 3, LayoutKind::Gradational, soft, h, Vec3(7.5 * h, 1.5 * h, 0.2 + 0.5 * h)));
  SimulationSettings sim = test::isolated();
  sim.threads = 1;
  sim.dtFraction = 0.25;
  sim.dtPeriod = PeriodRule::Vertex;
  auto world = test::worldOfBodies(parts, {Vec3(1, 0, 0), Vec3::Zero(), Vec3(0.6, 0, 0), Vec3(-0.4, 0, 0)}, sim, {0, 0, false});
  const RestModel& m = world->model();
  auto pairMomentum = [&](size_t first) {
    Vec3 p = Vec3::Zero();
    Real scale = 0;
    for (size_t b = first; b < first + 2; ++b)
      for (uint32_t u = m.bodies[b].vertexBegin; u < m.bodies[b].vertexEnd; ++u)
        p += m.mass[u] * world->state().velocities[u], scale += m.mass[u] * world->state().velocities[u].norm();
    return std::make_pair(p, scale);
  };
  const auto [p0, s0] = pairMomentum(0);
  const auto [p1, s1] = pairMomentum(2);
  Real removed = 0;
  for (int k = 0; k < 150; ++k) {
    world->step();
    removed += world->bodyContactStats().energyRemoved;
  }
  std::printf("  energy taken out by the cap %.3e J\n", removed);
  EXPECT_GT(removed, 0) << "the cap acted";
  EXPECT_LE((pairMomentum(0).first - p0).norm(), 1e-9 * s0);
  EXPECT_LE((pairMomentum(2).first - p1).norm(), 1e-9 * s1);
}

// Random pairs (shapes, sizes 6..10, E 1e4..1e7, speeds 1..20 m/s, who moves, offset, restitution
// and friction 0..1, dt_fraction 0.1 or 0.25): small enough for CI (docs/tests.md: a longer run).
void randomImpactIsSafe() {
  Impact c;
  const char* shapes[] = {"sphere", "box"};
  c.shapeA = shapes[*rc::gen::inRange(0, 2)], c.shapeB = shapes[*rc::gen::inRange(0, 2)];
  c.sizeA = *rc::gen::inRange(6, 11), c.sizeB = *rc::gen::inRange(6, 11);
  c.youngA = std::pow(10.0, *rc::gen::inRange(40, 71) / 10.0);
  c.youngB = std::pow(10.0, *rc::gen::inRange(40, 71) / 10.0);
  c.closing = *rc::gen::inRange(1, 21);
  c.shareA = *rc::gen::element(0.0, 0.5, 1.0);
  c.offset = *rc::gen::inRange(0, 6) / 10.0;
  c.restitution = *rc::gen::inRange(0, 11) / 10.0;
  c.friction = *rc::gen::inRange(0, 11) / 10.0;
  c.dtFraction = *rc::gen::element(0.1, 0.25);
  c.maxDuration = 0.1;
  const ImpactResult r = runImpact(c);
  RC_LOG() << c.shapeA << " " << c.sizeA << " E " << c.youngA << " vs " << c.shapeB << " " << c.sizeB << " E "
           << c.youngB << " at " << c.closing << " m/s share " << c.shareA << " offset " << c.offset << " e "
           << c.restitution << " mu " << c.friction << " dt_fraction " << c.dtFraction << ": " << describe(r) << "\n";
  RC_ASSERT(r.finite);
  RC_ASSERT(r.peak <= 1.02);
  RC_ASSERT(r.momentum <= 1e-9);
  RC_ASSERT(!r.parted || r.minDet > 0);
}

// GRADEL_PROPERTY_CASES (default 8) cases from a fixed seed (docs/tests.md: a longer run and what
// it found). Before the stage's energy cap (body_contact_energy.h) its third case failed: a 7^3 ball
// of E = 4e4 Pa into a 6^3 one of 1e4 Pa at rest at 1 m/s, restitution 0, dt_fraction 0.25, peak
// 1.039x (1.0020x with the cap).
TEST(Impacts, RandomPairsNeverInventEnergy) {
  rc::detail::TestParams params = rc::detail::configuration().testParams;
  params.maxSuccess = std::getenv("GRADEL_PROPERTY_CASES") ? std::atoi(std::getenv("GRADEL_PROPERTY_CASES")) : 8;
  if (!std::getenv("RC_PARAMS")) params.seed = 26;
  rc::detail::TestMetadata metadata;
  metadata.id = "Impacts/RandomPairsNeverInventEnergy";
  const auto result = rc::detail::checkTestable(&randomImpactIsSafe, metadata, params);
  if (!result.template is<rc::detail::SuccessResult>()) {
    std::ostringstream ss;
    rc::detail::printResultMessage(result, ss);
    FAIL() << ss.str();
  }
}

// The measurement behind the tests (not run by default): GRADEL_IMPACT_* settings, or a table
// of the issue's scenes. GRADEL_IMPACT_TRACE=n prints the energy every n steps; with it,
// GRADEL_IMPACT_DEEP=d [m] also lists each step's contacts found deeper than d (vertex, face,
// depth, normal, and the gap the step ended with).
TEST(Impacts, DISABLED_Measure) {
  auto env = [](const char* k, Real d) { return std::getenv(k) ? std::atof(std::getenv(k)) : d; };
  Impact c;
  c.closing = env("GRADEL_IMPACT_SPEED", 4);
  c.dtFraction = env("GRADEL_IMPACT_DT_FRACTION", 0.1);
  c.gap = env("GRADEL_IMPACT_GAP", 0.5);
  c.restitution = env("GRADEL_IMPACT_RESTITUTION", 0.5);
  c.friction = env("GRADEL_IMPACT_FRICTION", 0);
  c.offset = env("GRADEL_IMPACT_OFFSET", 0);
  c.shareA = env("GRADEL_IMPACT_SHARE", 0.5);
  c.sizeA = int(env("GRADEL_IMPACT_SIZE_A", 16)), c.sizeB = int(env("GRADEL_IMPACT_SIZE_B", 16));
  c.youngA = env("GRADEL_IMPACT_E_A", 1e5), c.youngB = env("GRADEL_IMPACT_E_B", 1e5);
  c.poisson = env("GRADEL_IMPACT_POISSON", 0);
  if (std::getenv("GRADEL_IMPACT_SHAPE_A")) c.shapeA = std::getenv("GRADEL_IMPACT_SHAPE_A");
  if (std::getenv("GRADEL_IMPACT_SHAPE_B")) c.shapeB = std::getenv("GRADEL_IMPACT_SHAPE_B");
  if (env("GRADEL_IMPACT_LARGE_STEP", 0) > 0) c.integrator = IntegratorKind::LargeStep;
  c.duration = env("GRADEL_IMPACT_DURATION", 0);
  c.maxDuration = env("GRADEL_IMPACT_MAX_DURATION", 0.25);
  const ImpactResult r = runImpact(c, int(env("GRADEL_IMPACT_TRACE", 0)));
  std::printf("%s\n", describe(r).c_str());
}

}  // namespace
}  // namespace gradel
