// The explicit step resolves contacts only for blocks of vertices that can touch a wall or a
// manipulator's swept bounds this step (World::stageVertices). That broad phase must change
// nothing: here every step is compared, bit for bit, with the same step taken without contacts
// and followed by the contact rules applied to every vertex (the narrow phase alone).
#include <gtest/gtest.h>

#include <cstring>

#include "gradel/world.h"
#include "test_support.h"

namespace gradel {
namespace {

using test::Body;
using test::makeBody;
using test::perturb;

// The narrow phase for one vertex, as World applies it (a bounce, then up to three inelastic
// passes for a vertex pinched between surfaces; walls last).
void resolveAll(const std::vector<Manipulator>& ms, const DomainSettings& d, int dim, const Vec3& previous,
                const StepStart& start, Vec3& x, Vec3& v) {
  const size_t surfaces = ms.size() + (d.enabled ? 1 : 0);
  for (int pass = 0; pass < 4; ++pass) {
    Real depth = 0;
    for (const Manipulator& m : ms)
      depth = std::max(depth, resolveManipulator(m, previous, x, v, pass == 0, &start).depth);
    depth = std::max(depth, resolveDomain(d, previous, x, v, dim, pass == 0, &start).depth);
    if (depth == 0 || surfaces < 2) break;
  }
}

bool sameBits(const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(Vec3)) == 0;
}

void checkBroadPhaseExact(const Body& b, int threads, const DomainSettings& d,
                          const std::vector<ManipulatorSettings>& ms, int steps) {
  SimulationSettings s;
  s.threads = threads;
  s.damping = 0.5;
  World w(b.model, s, d, ms);
  SimulationSettings free = s;
  World ref(b.model, free, DomainSettings{}, {});
  perturb(w, 0.2 * b.model->voxelSize, 0.3, 5);
  int touched = 0;
  for (int k = 0; k < steps; ++k) {
    ref.state() = w.state();
    const std::vector<Vec3> previous = w.state().positions, previousVelocity = w.state().velocities;
    // The manipulators over this step: from their pose now to their pose at t + dt.
    std::vector<Manipulator> poses = w.manipulators();
    for (Manipulator& m : poses) {
      m.previousPosition = m.position;
      m.position = m.settings.path.position(w.time() + w.dt());
      m.velocity = m.settings.path.velocity(w.time() + w.dt());
    }
    w.step();
    ref.step();
    State& r = ref.state();
    for (size_t i = 0; i < r.positions.size(); ++i) {
      const Vec3 before = r.positions[i];
      resolveAll(poses, d, b.model->dim, previous[i],
                 StepStart{previousVelocity[i], w.dt(), w.settings().integrator == IntegratorKind::SymplecticEuler},
                 r.positions[i], r.velocities[i]);
      touched += r.positions[i] != before;
    }
    ASSERT_TRUE(sameBits(w.state().positions, r.positions)) << "positions differ at step " << k;
    ASSERT_TRUE(sameBits(w.state().velocities, r.velocities)) << "velocities differ at step " << k;
  }
  EXPECT_GT(touched, 50) << "the scene must really have contacts";
}

TEST(BroadPhase, SkipsOnlyVerticesThatCannotTouch) {
  // A ball of > 2048 vertices (so that two threads really share it) pressed on the floor by a
  // fast sphere that crosses a quarter of it in a few steps, and a cylinder whose axis is tilted
  // (its bounding sphere is what the broad phase uses).
  Body b = makeBody("sphere", 26, 3, LayoutKind::Gradational);
  DomainSettings d;
  d.enabled = true;
  d.min = Vec3(-0.1, 0.002, -0.1), d.max = Vec3(0.4, 0.4, 0.24);
  ManipulatorSettings fast;
  fast.radius = 0.04, fast.restitution = 1.0;
  fast.path.keys = {{0.0, Vec3(-0.04, 0.13, 0.13), std::nullopt}, {0.004, Vec3(0.08, 0.13, 0.13), std::nullopt}};
  ManipulatorSettings cyl;
  cyl.shape = ManipulatorShape::Cylinder;
  cyl.radius = 0.02, cyl.halfLength = 0.06, cyl.axis = Vec3(1, 0.3, 0.2).normalized(), cyl.friction = 0.5;
  cyl.path.keys = {{0.0, Vec3(0.13, 0.3, 0.13), std::nullopt}, {0.01, Vec3(0.13, 0.24, 0.13), std::nullopt}};
  for (int threads : {1, 2}) checkBroadPhaseExact(b, threads, d, {fast, cyl}, 60);
}

TEST(BroadPhase, TwoDimensionalCircles) {
  Body b = makeBody("sphere", 40, 2, LayoutKind::Gradational);
  DomainSettings d;
  d.enabled = true;
  d.min = Vec3(-0.1, 0.003, -1), d.max = Vec3(0.39, 0.5, 1);
  ManipulatorSettings circle;
  circle.shape = ManipulatorShape::Circle;
  circle.radius = 0.05;
  circle.path.keys = {{0.0, Vec3(-0.05, 0.2, 0), std::nullopt}, {0.01, Vec3(0.1, 0.2, 0), std::nullopt}};
  checkBroadPhaseExact(b, 1, d, {circle}, 60);
}

}  // namespace
}  // namespace gradel
