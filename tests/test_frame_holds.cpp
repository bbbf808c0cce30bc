// The held contacts of the frame-size steps (projective.h: one-sided holds as an active set over
// the step's passes, each pass's PCG run to convergence): a hold let go on an early pass's inexact
// reaction is held again once its vertex is behind its surface's plane (issue 26 item 1). Before, a body resting on the floor
// could lose every floor hold in the first passes of a step, fall through the floor for the rest
// of it and be put back up by the last contact pass: a step's fall of elastic energy at once.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "gradel/scene.h"
#include "gradel/world.h"

namespace gradel {
namespace {

Scene graspBody(IntegratorKind integrator, Real dt, Real stiffnessFactor) {
  Scene s = loadScene(std::string(GRADEL_SOURCE_DIR) + "/scenes/grasp-body.json");
  s.simulation.integrator = integrator;
  s.simulation.dt = dt;
  s.simulation.threads = 1;
  for (BodySettings& b : s.bodies) b.material.youngsModulus *= stiffnessFactor;  // (no regions in this scene)
  return s;
}

// grasp-body at dt = 1/30 s: the block rests on the floor, 5 mm from the ball, until the cylinder
// pushes the ball into it (t > 0.33 s). Before, at t = 0.167 and 0.300 s a step let go of the
// block's floor holds and ended with 2.16 J and 1.46 J in the block (the explicit run's peak of the
// whole scene: 0.195 J); now its elastic energy stays at its resting sag, below 2e-4 J.
TEST(FrameHolds, RestingBlockKeepsItsFloorHolds) {
  for (IntegratorKind integrator : {IntegratorKind::LargeStep, IntegratorKind::Implicit}) {
    BuiltScene b = buildScene(graspBody(integrator, 1.0 / 30, 1));
    World& w = *b.world;
    Real peak = 0;
    while (w.time() < 0.33) {
      w.step();
      peak = std::max(peak, w.bodyMetrics().at(1).elasticEnergy);
    }
    EXPECT_LT(peak, 1e-3) << int(integrator);
    std::printf("[ measured ] integrator %d: the block's peak elastic energy %.3g J\n", int(integrator), peak);
  }
}

// The whole grasp-body scene, E x1 to x1000, with the large step: the peak of kinetic + elastic
// energy against the explicit run's (bench/large_energy.py), every element upright at the end.
// History at dt = 1/30 s: before the holds' active set 11.2x at E x1 and 47x at E x10 (exit 3);
// with it, 1.75x, 6.5x, 9.3x and 9.9x. The frictional holds (stuck at the step's start, Coulomb's
// cone, docs/speed.md) alone made E x10 11.5x and from E x100 the run diverged: the ball no longer
// sank along the cylinder out of the squeeze, the whole push reached the soft pair constraints
// between the bodies (k 4-90 N/m), and the body-contact stage pushed the ball out of the block with
// 5-36 J; so a body in a pair constraint kept the plain holds, whose ratchet dragged the ball
// 4.5 mm down into the floor (5x the explicit run's elastic energy at rest). Now every body has
// the frictional holds, the pairs' k is at least 0.1 / (J D^-1 J^T), and a body in a pair
// constraint does not slip as a whole (projective.cpp): at 1/60 s within 5 % of the explicit peak
// (main: 0.96 / 3.61 / 12.2 / 14.0), at 1/30 s 0.76 / 1.96 / 3.05 / 3.09 (the push's last step
// squeezes the ball twice the explicit run's; it relaxes over 0.3 s to the explicit rest state).
struct GraspBodyCase {
  Real dt, factor, explicitPeak, bound;
};
void expectGraspBody(const std::vector<GraspBodyCase>& cases) {
  for (const GraspBodyCase& c : cases) {
    BuiltScene b = buildScene(graspBody(IntegratorKind::LargeStep, c.dt, c.factor));
    World& w = *b.world;
    Real peak = 0;
    while (w.time() < 1.0 - 1e-9) {
      w.step();
      const Metrics m = w.metrics();
      peak = std::max(peak, m.kineticEnergy + m.elasticEnergy);
    }
    EXPECT_LT(peak, c.bound * c.explicitPeak) << "E x" << c.factor << ", dt " << c.dt;
    EXPECT_GT(w.metrics().minElementDet, 0) << "E x" << c.factor << ", dt " << c.dt;
    std::printf("[ measured ] E x%g, dt 1/%.0f s: peak %.4g J, %.3g x the explicit run's\n", c.factor, 1 / c.dt, peak,
                peak / c.explicitPeak);
  }
}
TEST(FrameHolds, GraspBodyWithinFivePercentOfTheExplicitPeakAtSixtiethSecond) {
  expectGraspBody({{1.0 / 60, 1, 0.195495, 1.05},
                   {1.0 / 60, 10, 0.451892, 1.05},
                   {1.0 / 60, 100, 4.15208, 1.05},
                   {1.0 / 60, 1000, 42.4997, 1.05}});
}
TEST(FrameHolds, GraspBodyAtThirtiethSecond) {
  expectGraspBody({{1.0 / 30, 1, 0.195495, 1.05},
                   {1.0 / 30, 10, 0.451892, 2.2},
                   {1.0 / 30, 100, 4.15208, 3.4},
                   {1.0 / 30, 1000, 42.4997, 3.4}});
}

Scene shippedScene(const char* name, IntegratorKind integrator, Real dt, Real stiffnessFactor) {
  Scene s = loadScene(std::string(GRADEL_SOURCE_DIR) + "/scenes/" + name + ".json");
  s.simulation.integrator = integrator;
  s.simulation.dt = dt;
  s.simulation.threads = 1;
  for (BodySettings& b : s.bodies) b.material.youngsModulus *= stiffnessFactor;  // (no regions)
  return s;
}

struct GraspRun {
  Real peak = 0, startHeight = 0, endHeight = 0, endMinDet = 0;
};
// The peak of kinetic + elastic energy over the scene's duration, and the body's centre of mass
// height (from its gravity energy) at the start and the end.
GraspRun runGrasp(const char* name, IntegratorKind integrator, Real dt, Real factor) {
  const Scene scene = shippedScene(name, integrator, dt, factor);
  BuiltScene b = buildScene(scene);
  World& w = *b.world;
  Real mass = 0;
  for (Real m : b.world->model().mass) mass += m;
  const Real g = -scene.simulation.gravity.y();
  GraspRun r;
  r.startHeight = w.metrics().gravityEnergy / (mass * g);
  while (w.time() < scene.output.duration - 1e-9) {
    w.step();
    const Metrics m = w.metrics();
    r.peak = std::max(r.peak, m.kineticEnergy + m.elasticEnergy);
  }
  const Metrics m = w.metrics();
  r.endHeight = m.gravityEnergy / (mass * g), r.endMinDet = m.minElementDet;
  return r;
}

// Issue 26 item 1: the frame-size steps' grasps within 5 % of the explicit run's peak of kinetic +
// elastic energy (bench/large_energy.py; the explicit peaks of bench/results/2026-11-27-large-energy.csv).
// Before (the holds stuck where the contact pass put them, from a first solve that let the ball
// fall a whole step unsupported, and never slipped): grasp-wall 1.19 / 2.46 at E x1 and dt = 1/60 /
// 1/30 s, 1.25 / 2.58 at E x10; grasp-two 1.30 / 2.77 and 1.22 / 2.81 (docs/speed.md).
struct GraspCase {
  IntegratorKind integrator;
  Real dt, factor, explicitPeak;
};
// Each case's peak within 5 % of the explicit run's, every element upright at the end, and the
// ball's centre at least `rise` [m] higher at the end than at the start.
void expectGrasps(const char* scene, const std::vector<GraspCase>& cases, Real rise) {
  for (const GraspCase& c : cases) {
    const GraspRun r = runGrasp(scene, c.integrator, c.dt, c.factor);
    EXPECT_LT(r.peak, 1.05 * c.explicitPeak) << scene << ", E x" << c.factor << ", dt " << c.dt;
    EXPECT_GT(r.endMinDet, 0);
    EXPECT_GT(r.endHeight, r.startHeight + rise) << scene << ", E x" << c.factor << ", dt " << c.dt;
    std::printf("[ measured ] %s, E x%g, dt 1/%.0f s: peak %.4g J, %.3g x the explicit run's; height %.4f -> %.4f m\n",
                scene, c.factor, 1 / c.dt, r.peak, r.peak / c.explicitPeak, r.startHeight, r.endHeight);
  }
}

// The ball stays up on the floor: its centre 2.7 mm down at the end, its sag (before, the side
// holds dragged it down into the floor: 6 mm at 1/60 s, 11 mm at 1/30 s; the explicit run 2 mm).
TEST(FrameHolds, GraspWallWithinFivePercentOfTheExplicitPeak) {
  expectGrasps("grasp-wall",
               {{IntegratorKind::LargeStep, 1.0 / 60, 1, 0.208306},
                {IntegratorKind::LargeStep, 1.0 / 30, 1, 0.208306},
                {IntegratorKind::Implicit, 1.0 / 60, 10, 1.64163},
                {IntegratorKind::LargeStep, 1.0 / 30, 10, 1.64163}},
               -4.5e-3);
}

// The spheres lift the ball 2 cm (the explicit run: its centre 1.7 cm up; before, at 1/30 s, it
// slid down between them and ended lower than it started).
TEST(FrameHolds, GraspTwoWithinFivePercentOfTheExplicitPeakAndLifts) {
  expectGrasps("grasp-two",
               {{IntegratorKind::LargeStep, 1.0 / 60, 1, 0.390817},
                {IntegratorKind::Implicit, 1.0 / 30, 1, 0.390817},
                {IntegratorKind::LargeStep, 1.0 / 60, 10, 3.66899},
                {IntegratorKind::LargeStep, 1.0 / 30, 10, 3.66899}},
               0.012);
}

// A box resting on a floor with friction 0.5, gravity tilted: below its friction angle (tan 0.3)
// it stays, above it (tan 0.8) it slides as Coulomb's block does, 0.287 m in 0.5 s, within 15 %
// (0.297 / 0.306 m at dt = 1/60 / 1/30 s; main 0.294 / 0.306 m; the explicit run 0.057 m). The
// cone is what lets it go (stuck at the step's start without it, a hold never slips), the body's
// common slip what lets it go fast enough: with the holds' own return mapping alone, whose k is
// ~1000x the stiffness of the body's slide, 0.077 / 0.026 m.
TEST(FrameHolds, BoxOnATiltedFloorSticksBelowItsFrictionAngleAndSlidesAbove) {
  for (Real dt : {1.0 / 60, 1.0 / 30})
    for (Real slope : {0.3, 0.8}) {
      const Real angle = std::atan(slope), g = 9.81;
      char gravity[96];
      std::snprintf(gravity, sizeof gravity, "[%.17g, %.17g, 0]", g * std::sin(angle), -g * std::cos(angle));
      char json[1024];
      std::snprintf(json, sizeof json, R"({
        "body": {"shape": "box", "size": 6, "voxel_size": 0.01},
        "material": {"youngs_modulus": 1e5, "density": 1000},
        "simulation": {"integrator": "large_step", "dt": %.17g, "damping": 0, "gravity": %s, "threads": 1},
        "domain": {"min": [-0.1, 0, -0.3], "max": [1, 0.5, 0.3], "restitution": 0, "friction": 0.5}})",
                    dt, gravity);
      BuiltScene b = buildScene(parseScene(json, "tilted.json"));
      World& w = *b.world;
      auto meanX = [&] {
        Real x = 0;
        for (const Vec3& p : w.state().positions) x += p.x();
        return x / Real(w.state().positions.size());
      };
      const Real x0 = meanX();
      while (w.time() < 0.5 - 1e-9) w.step();
      const Real moved = meanX() - x0;
      if (slope < 0.5) {
        EXPECT_LT(std::abs(moved), 1e-3) << "dt " << dt;
      } else {
        EXPECT_GT(moved, 0.287 * 0.85) << "dt " << dt;
        EXPECT_LT(moved, 0.287 * 1.15) << "dt " << dt;
      }
      EXPECT_GT(w.metrics().minElementDet, 0);
      std::printf("[ measured ] dt 1/%.0f s, slope %.1f: moved %.4f m\n", 1 / dt, slope, moved);
    }
}

// The strike scene (a sphere manipulator hits the floating ball at 1.25 m/s, restitution 1) with
// the large step, E x1 to x1000 at dt = 1/60 and 1/30 s: the peak of kinetic + elastic energy
// within 5 % of the explicit run's (bench/large_energy.py; the explicit peaks of
// bench/results/2026-11-30-large-energy-frictional-holds.csv), and at E x1 the ball leaves the hit
// with the explicit run's energy (0.314 J at t = 0.3 s) within 20 %. At 1/30 s the striker moves
// more than its radius in a step and its path is swept (World::sweepManipulatorPaths). Before,
// the sweep sent each vertex it hit off with the striker's reflected velocity, as a free particle,
// and the held solve dragged the ball after them: 1.60x the explicit peak at E x1, the ball flying
// with 0.57 J at t = 0.3 s (0.51x the peak from E x10, the explicit ball taking more of the hit).
// Now a hit vertex rides on the striker and the held solve hands the hit to the whole ball.
TEST(FrameHolds, SweptStrikeWithinFivePercentOfTheExplicitPeak) {
  const struct { Real factor, explicitPeak; } cases[] = {{1, 0.611538}, {10, 2.62904}, {100, 2.81975}, {1000, 2.82114}};
  for (const auto& c : cases)
    for (Real dt : {1.0 / 60, 1.0 / 30}) {
      BuiltScene b = buildScene(shippedScene("strike", IntegratorKind::LargeStep, dt, c.factor));
      World& w = *b.world;
      Real peak = 0, afterHit = 0;
      while (w.time() < 1.0 - 1e-9) {
        w.step();
        const Metrics m = w.metrics();
        peak = std::max(peak, m.kineticEnergy + m.elasticEnergy);
        if (std::abs(w.time() - 0.3) < 1e-9) afterHit = m.kineticEnergy + m.elasticEnergy;
      }
      EXPECT_LT(peak, 1.05 * c.explicitPeak) << "E x" << c.factor << ", dt " << dt;
      EXPECT_GT(peak, 0.1 * c.explicitPeak) << "the ball was hit: E x" << c.factor << ", dt " << dt;
      if (c.factor == 1 && dt > 1.0 / 45) {  // (unswept at 1/60 s, the ball takes 0.106 J: a third)
        EXPECT_GT(afterHit, 0.8 * 0.314) << "dt " << dt;
        EXPECT_LT(afterHit, 1.2 * 0.314) << "dt " << dt;
      }
      EXPECT_GT(w.metrics().minElementDet, 0);
      std::printf("[ measured ] strike, E x%g, dt 1/%.0f s: peak %.4g J, %.3g x the explicit run's; %.4g J at t = 0.3 s\n",
                  c.factor, 1 / dt, peak, peak / c.explicitPeak, afterHit);
    }
}

}  // namespace
}  // namespace gradel
