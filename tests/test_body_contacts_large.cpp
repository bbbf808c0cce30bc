// Body-body contact at frame-size steps (issue 12, item 2): the implicit and large-step
// integrators carry the contacts as constraints of their solve (body_contacts.h,
// BodyContacts::proximity; projective.h, pair constraints), the post-step projection stays the
// safety net. The scenes run at dt = 1/60 s.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <limits>

#include "gradel/body_contacts.h"
#include "gradel/scene.h"
#include "gradel/shapes.h"
#include "gradel/world.h"
#include "test_support.h"

namespace gradel {
namespace {

struct FrameRun {
  BuiltScene built;
  FrameRun(const std::string& file, IntegratorKind integrator, Real dt, int threads = 1)
      : built(buildScene(configure(file, integrator, dt, threads))) {}
  explicit FrameRun(const Scene& s) : built(buildScene(s)) {}
  static Scene configure(const std::string& file, IntegratorKind integrator, Real dt, int threads) {
    Scene s = loadScene(std::string(GRADEL_SOURCE_DIR) + "/scenes/" + file);
    s.simulation.integrator = integrator;
    s.simulation.dt = dt;
    s.simulation.threads = threads;
    return s;
  }
  World& world() { return *built.world; }
  const RestModel& model() { return world().model(); }
  Vec3 centre(size_t i, bool velocity = false) {
    const BodyRange& r = model().bodies[i];
    const std::vector<Vec3>& y = velocity ? world().state().velocities : world().state().positions;
    Vec3 c = Vec3::Zero();
    Real m = 0;
    for (uint32_t u = r.vertexBegin; u < r.vertexEnd; ++u) c += model().mass[u] * y[u], m += model().mass[u];
    return c / m;
  }
  Real top(size_t i) {
    const BodyRange& r = model().bodies[i];
    Real t = -std::numeric_limits<Real>::infinity();
    for (uint32_t u = r.vertexBegin; u < r.vertexEnd; ++u) t = std::max(t, world().state().positions[u].y());
    return t;
  }
  Vec3 momentum() {
    Vec3 p = Vec3::Zero();
    for (size_t u = 0; u < model().numVertices(); ++u) p += model().mass[u] * world().state().velocities[u];
    return p;
  }
  Real momentumScale() {
    Real s = 0;
    for (size_t u = 0; u < model().numVertices(); ++u) s += model().mass[u] * world().state().velocities[u].norm();
    return s;
  }
  // Boundary vertices of any body inside any other (test::verticesInsideOtherBodies).
  size_t inside() { return test::verticesInsideOtherBodies(world()); }
};

bool verbose() { return std::getenv("GRADEL_VERBOSE") != nullptr; }

// The stack's settled state with the explicit integrator (the reference): top of the top block.
Real explicitStackTop() {
  static const Real top = [] {
    FrameRun r("stack.json", IntegratorKind::SymplecticEuler, 0);
    while (r.world().time() < 1.0) r.world().step();
    if (verbose())
      std::printf("explicit: top %.5f, centres %.5f %.5f %.5f\n", r.top(2), r.centre(0).y(), r.centre(1).y(),
                  r.centre(2).y());
    return r.top(2);
  }();
  return top;
}

void stackSettles(IntegratorKind integrator) {
  const Real reference = explicitStackTop();
  FrameRun r("stack.json", integrator, 1.0 / 60);
  size_t insideSteps = 0;
  Real maxLateSpeed = 0, minTop = 1e300, maxTop = -1e300;
  while (r.world().time() < 2.0 - 1e-9) {
    r.world().step();
    const size_t in = r.inside();
    if (in) ++insideSteps;
    if (r.world().time() > 1.5) {
      for (size_t i = 0; i < 3; ++i) maxLateSpeed = std::max(maxLateSpeed, r.centre(i, true).norm());
      minTop = std::min(minTop, r.top(2)), maxTop = std::max(maxTop, r.top(2));
    }
    if (verbose())
      std::printf("t %.3f inside %zu centres %.5f %.5f %.5f top %.5f speeds %.4f %.4f %.4f contacts %zu\n",
                  r.world().time(), in, r.centre(0).y(), r.centre(1).y(), r.centre(2).y(), r.top(2),
                  r.centre(0, true).norm(), r.centre(1, true).norm(), r.centre(2, true).norm(),
                  r.world().bodyContactStats().contacts);
  }
  EXPECT_EQ(insideSteps, 0u) << "steps that ended with a vertex inside another body";
  EXPECT_LT(maxLateSpeed, 0.01) << "block centres at rest over the last 0.5 s [m/s]";
  EXPECT_NEAR(minTop, reference, 0.03 * reference) << "stack height vs the explicit run's";
  EXPECT_NEAR(maxTop, reference, 0.03 * reference);
  EXPECT_LT(maxTop - minTop, 0.002) << "the top does not drift or jitter over the last 0.5 s [m]";
}

// Two balls head on (no walls, no gravity) at dt = 1/60 s, each at `speed` [m/s] towards the
// other (0: the scene's 0.5 m/s): linear momentum through the collision, no vertex inside the
// other ball after any step, and they part. At 1 m/s each they close by 3.3 cm a step, more than
// the balls' voxel (1 cm); at 5 m/s by 17 cm, more than a ball's diameter (10 cm).
// `insideStepsAllowed`: at 5 m/s each a ball is crushed to half its size within a step and its
// surface can fold through itself, where the stage's pseudo-normal inside test (body_contacts.h)
// and this test's winding number disagree: one step of 30 with a vertex inside, by the winding
// number, on one build and none on another (rounding).
void twoBallsCollide(IntegratorKind integrator, Real speed, size_t insideStepsAllowed = 0) {
  Scene s = FrameRun::configure("two-balls.json", integrator, 1.0 / 60, 1);
  if (speed > 0) s.bodies[0].velocity = Vec3(speed, 0, 0), s.bodies[1].velocity = Vec3(-speed, 0, 0);
  const Real closing = s.bodies[0].velocity.x() - s.bodies[1].velocity.x();
  FrameRun r(s);
  const Vec3 p0 = r.momentum();
  const Real scale = r.momentumScale();
  Real worst = 0;
  size_t insideSteps = 0;
  int takeBacks = 0;
  while (r.world().time() < 0.5 - 1e-9) {
    r.world().step();
    worst = std::max(worst, (r.momentum() - p0).norm() / scale);
    if (r.inside()) ++insideSteps;
    takeBacks += r.world().bodyContactStats().takeBacks > 0;
    if (verbose())
      std::printf("t %.3f dp %.3g v %.4f %.4f gap %.5f contacts %zu rounds %d taken back to %.3g\n", r.world().time(),
                  (r.momentum() - p0).norm() / scale, r.centre(0, true).x(), r.centre(1, true).x(),
                  r.centre(1).x() - r.centre(0).x(), r.world().bodyContactStats().contacts,
                  r.world().bodyContactStats().rounds, r.world().bodyContactStats().takenBackTo);
  }
  const Real parting = r.centre(1, true).x() - r.centre(0, true).x();
  if (verbose())
    std::printf("closing %.2f m/s, parting %.3f m/s (ratio %.3f), steps taken back %d\n", closing, parting,
                parting / closing, takeBacks);
  EXPECT_LE(worst, 1e-9) << "linear momentum, relative to sum m |v|";
  EXPECT_LE(insideSteps, insideStepsAllowed) << "steps that ended with a vertex inside the other ball";
  EXPECT_LT(r.centre(0, true).x(), 0.0) << "ball 0 moves back";
  EXPECT_GT(r.centre(1, true).x(), 0.0) << "ball 1 moves back";
  EXPECT_LT(parting, closing) << "no energy from the contacts [m/s]";
}

TEST(BodyContactsLarge, TwoBallsAtLargeStep) { twoBallsCollide(IntegratorKind::LargeStep, 0); }
TEST(BodyContactsLarge, TwoBallsImplicit) { twoBallsCollide(IntegratorKind::Implicit, 0); }
TEST(BodyContactsLarge, TwoFastBallsAtLargeStep) {
  for (Real speed : {1.0, 2.0}) {
    SCOPED_TRACE(speed);
    twoBallsCollide(IntegratorKind::LargeStep, speed);
  }
  twoBallsCollide(IntegratorKind::LargeStep, 5.0, 1);
}
TEST(BodyContactsLarge, TwoFastBallsImplicit) {
  for (Real speed : {1.0, 2.0}) {
    SCOPED_TRACE(speed);
    twoBallsCollide(IntegratorKind::Implicit, speed);
  }
  twoBallsCollide(IntegratorKind::Implicit, 5.0, 1);
}
// At 10 m/s each (33 cm a step) the solve's contacts leave vertices inside and the post-step
// stage's last resort takes the balls back towards where they were (body_contacts.h). A vertex
// left less than kTakeBackDepth (0.1 voxel) inside is pushed out again in the next step instead of
// taking the balls back (issue 26: the take-back kept the step's velocities and made energy):
// one step of 30 ends with such a vertex on the sanitizer build (portable rounding), none on the
// Release build.
TEST(BodyContactsLarge, TwoBallsAtTenMetresPerSecond) { twoBallsCollide(IntegratorKind::LargeStep, 10.0, 1); }

// The stack and two bigger balls (2 threads take part: > 2048 vertices) at large step: the same
// state hash at 1 and 2 threads.
TEST(BodyContactsLarge, SameStateAtOneAndTwoThreads) {
  for (const char* file : {"stack.json", "two-balls.json"}) {
    std::vector<uint64_t> hashes;
    for (int threads : {1, 2}) {
      Scene s = FrameRun::configure(file, IntegratorKind::LargeStep, 1.0 / 60, threads);
      if (std::string(file) == "two-balls.json")
        for (size_t i = 0; i < 2; ++i) {
          s.bodies[i].shape = presetShape("sphere", 14, 3);
          s.bodies[i].position = Vec3(i == 0 ? -0.1405 : 0.0005, -0.07, -0.07);
        }
      BuiltScene b = buildScene(s);
      if (std::string(file) == "two-balls.json") {
        EXPECT_GE(b.world->model().numVertices(), 2048u);
      }
      for (int k = 0; k < 30; ++k) b.world->step();
      hashes.push_back(b.world->stateHash());
    }
    EXPECT_EQ(hashes[0], hashes[1]) << file;
  }
}

TEST(BodyContactsLarge, StackSettlesAtLargeStep) { stackSettles(IntegratorKind::LargeStep); }
TEST(BodyContactsLarge, StackSettlesImplicit) { stackSettles(IntegratorKind::Implicit); }

}  // namespace
}  // namespace gradel
