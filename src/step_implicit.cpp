// The implicit integrator's advance (projective.h, backward Euler), also the large step's near
// contacts: a solve, the obstacle contacts found on it, a second solve with those vertices held
// and the body contacts as pair constraints, the contact rules on the result.
#include <algorithm>

#include "step_context.h"

namespace gradel {

// Implicit step (projective.h): solve with pinned vertices eliminated, then the same contact
// stage as the explicit path (positions projected, velocity rules applied to the derived
// velocities (x_new - x_old) / dt). `largeStep` (a large step near contacts): fast manipulators
// are swept along their paths.
// The contact pass finds the vertices that ended inside a surface; the step is solved again
// from its start with them held at their projected positions, so that the support reaches the
// whole body within the step (projecting only those vertices afterwards lets a body sink and
// crush at frame-size steps). A last pass then applies the contact rules to the final state.
// The holds are one-sided (projective.h): each carries the direction it pushed its vertex out.
// Contacts between bodies: every boundary vertex that could reach another body within the step
// is a pair constraint of the second solve (projective.h); the body-contact stage after the
// step (stageBodyContacts) is the safety net.
void World::stepImplicit(bool largeStep) {
  StepContext& c = *scratch_;
  if (!projective_) projective_ = std::make_unique<ProjectiveSolver>(*model_, dt_, pinSet_.vertices);
  projective_->setTeam(frameStepTeam());  // the factor's solves (the same bits at any count, projective.h)
  if (c.obstacles) c.previousPositions = state_.positions, c.previousVelocities = state_.velocities;
  c.contactDepth.assign(model_->numVertices(), 0.0);
  const State start = state_;
  const std::vector<Vec3> targets = pinTargets(c.tNext);
  projective_->step(state_.positions, state_.velocities, state_.rotations, c.gravity, sim_.damping,
                    sim_.implicitIterations, targets, sim_.rotationIterations);
  moveManipulators(c.tNext);
  if (c.obstacles || c.bodyContacts) {
    const std::vector<Vec3> freeEnd = state_.positions;
    std::vector<uint64_t> pairKeys;
    std::vector<PairConstraint> pairs;
    if (c.bodyContacts) pairs = stepBodyPairs(start.positions, freeEnd, pairKeys);
    HeldContacts held;
    if (c.obstacles) held = heldObstacleContacts(freeEnd, largeStep);
    if (!held.vertices.empty() || !pairs.empty()) {
      solveHeld(start, targets, held, pairs);
      keepBodyPairLambdas(pairs, pairKeys);
      if (c.obstacles) {
        if (largeStep) sweepManipulatorPaths(c.tNext - dt_);
        stageContacts(0, model_->numVertices());
      }
    } else {
      clearBodyPairLambdas();
    }
  }
  finishFrameStep(c.tNext);
}

// The vertices the obstacle contacts moved out of a surface at the end of the first solve
// (freeEnd), each held where they left it, with the direction of its push and the surface.
// The vertices a swept manipulator hit are held where the sweep left them, as those the contact
// pass pushed out (left free, the second solve restarted without them, or without a second
// solve they kept their flight alone: at dt = 1/30 s the struck ball's E x1000 step ended with
// 7,770 J of elastic energy, the explicit run's peak 2.8 J).
World::HeldContacts World::heldObstacleContacts(const std::vector<Vec3>& freeEnd, bool largeStep) {
  StepContext& c = *scratch_;
  std::vector<Real> swept;
  if (largeStep) sweepManipulatorPaths(c.tNext - dt_), swept = c.contactDepth;
  stageContacts(0, model_->numVertices());
  HeldContacts held;
  for (uint32_t i = 0; i < model_->numVertices(); ++i) {
    const Vec3 push = state_.positions[i] - freeEnd[i];
    if ((c.contactDepth[i] > 0 || (!swept.empty() && swept[i] > 0)) && push.norm() > 0)
      held.vertices.push_back(i), held.at.push_back(state_.positions[i]), held.normal.push_back(push.normalized());
  }
  // Every held vertex was moved by a surface (a wall: K + its kWalls index), with its friction:
  // a hold on a frictionless surface slides (projective.h).
  const size_t K = manipulators_.size();
  // (A body in a pair constraint of the step has these holds too: kept where the contact pass put
  // them, without a cone, a ball a cylinder pressed into a soft block (grasp-body) was dragged
  // down into the floor by the ratchet below and ended 4.5 mm lower than the explicit run's,
  // storing 5x its elastic energy at rest; that it no longer slides out of the squeeze needs pair
  // constraints stiff enough for the push (projective.h).)
  held.slip.assign(held.vertices.size(), Vec3::Zero());
  for (size_t j = 0; j < held.vertices.size(); ++j) {
    const uint32_t i = held.vertices[j];
    held.surface.push_back(c.contactSurface[i]);
    const size_t k = size_t(std::max(0, held.surface.back()));
    held.friction.push_back(k < K ? manipulators_[k].settings.friction : domain_.friction);
    if (!(held.friction.back() > 0) || (!swept.empty() && swept[i] > 0) || held.surface.back() < 0) continue;
    // A hold with friction sticks where the vertex was at the step's start, carried with its
    // surface (the anchor), put on the surface along the surface's normal there; it slips only by
    // Coulomb's cone in the held solve (projective.h). Held where the contact pass put it (before),
    // its target came from the first solve, which lets the body fall a whole step unsupported
    // (dt^2 g = 1.1 cm at 1/30 s), and the contact pass takes back a slip only up to friction x
    // the depth it pushed (contacts.cpp, made for the explicit step's small steps): the side holds
    // of a grasp were set lower every step and dragged the ball down into the floor (grasp-wall at
    // E x1, 1/30 s: its centre 0.8 cm down, 2.5x the explicit run's elastic energy; with gravity
    // off, 0.16 J against the explicit 0.18 J). On the contact's plane instead of the surface, a
    // grasping sphere's holds sat up to 0.9 mm inside the ball (the free solve moves a squeezed
    // rim vertex ~7 mm along the sphere, whose tangent plane there is outside it): 7 % more energy.
    const Vec3 x0 = c.previousPositions[i];
    Vec3 n = Vec3::Zero(), carry = Vec3::Zero();
    if (k < K) {
      const Manipulator& mp = manipulators_[k];
      carry = mp.position - mp.previousPosition;
      const Real d = mp.signedDistance(x0 + carry, &n);
      held.at[j] = x0 + carry - (d - 1e-9 * mp.settings.radius) * n;
    } else {
      const int wall = int(k - K), a = wall / 2;
      n[a] = wall % 2 ? -1 : 1;
      carry = wallVelocity_[size_t(wall)] * dt_;
      held.at[j] = x0 + carry;
      held.at[j][a] = wall % 2 ? domain_.max[a] : domain_.min[a];
    }
    held.normal[j] = n;
    // Its first guess of slip: its sliding over the surface at the step's start velocity (a body
    // sliding on the floor goes on sliding from the first pass; the cone takes back what it must).
    held.slip[j] = c.previousVelocities[i] * dt_ - carry;
  }
  held.letGo.assign(held.vertices.size(), 0);
  touchingAtStart(held);
  return held;
}

// The vertices on a surface at the step's start that the first solve took off it: held too,
// let go at first, so that the held solve's passes hold them once they go behind the surface's
// plane (the one-sided holds, projective.h). Found only from the first solve's end, a vertex of a
// squeezed contact's rim that the free solve took away from the surface was pushed into it by
// the held solve and out again by the last contact pass: a ball grasped between two spheres at
// dt = 1/60 s took turns of 19 and 10 holds with 8 and 17 vertices put back out, up to 0.45 mm,
// by that pass in every step (it stored 7 % more than the explicit squeeze). On a surface:
// within 1e-3 voxel of it (the contact pass leaves a vertex a skin of 1e-9 x its radius outside),
// where it was at the step's start, carried with its surface.
void World::touchingAtStart(HeldContacts& held) const {
  const StepContext& c = *scratch_;
  const size_t K = manipulators_.size();
  const Real near = 1e-3 * model_->voxelSize;
  std::vector<char> isHeld(model_->numVertices(), 0);
  for (uint32_t i : held.vertices) isHeld[i] = 1;
  for (uint32_t i = 0; i < model_->numVertices(); ++i) {
    if (isHeld[i]) continue;
    const Vec3& x0 = c.previousPositions[i];
    int surface = -1;
    Vec3 at = Vec3::Zero(), normal = Vec3::Zero();
    for (size_t k = 0; k < K && surface < 0; ++k) {
      const Manipulator& mp = manipulators_[k];
      if (mp.settings.shape == ManipulatorShape::Blade) continue;
      const Vec3 carried = x0 + (mp.position - mp.previousPosition);
      Vec3 n;
      const Real d = mp.signedDistance(carried, &n);
      if (d >= 0 && d < near) surface = int(k), at = carried - d * n, normal = n;
    }
    for (int a = 0; a < model_->dim && surface < 0 && domain_.enabled; ++a)
      for (int side = 0; side < 2 && surface < 0; ++side) {
        const int wall = 2 * a + side;
        const Vec3 carried = x0 + wallVelocity_[size_t(wall)] * dt_;
        const Real d = side == 0 ? carried[a] - domain_.min[a] : domain_.max[a] - carried[a];
        if (d >= 0 && d < near) {
          surface = int(K) + wall, at = carried, normal = Vec3::Zero();
          at[a] = side == 0 ? domain_.min[a] : domain_.max[a], normal[a] = side == 0 ? 1 : -1;
        }
      }
    if (surface < 0) continue;
    held.vertices.push_back(i), held.at.push_back(at), held.normal.push_back(normal);
    held.surface.push_back(surface);
    held.friction.push_back(size_t(surface) < K ? manipulators_[size_t(surface)].settings.friction : domain_.friction);
    held.letGo.push_back(1);
    const Vec3 carry = size_t(surface) < K ? Vec3(manipulators_[size_t(surface)].position -
                                                  manipulators_[size_t(surface)].previousPosition)
                                           : Vec3(wallVelocity_[size_t(surface) - K] * dt_);
    held.slip.push_back(c.previousVelocities[i] * dt_ - carry);
  }
}

// The body contacts of this step as pair constraints: found at the start of the step (x0), where
// no vertex is inside another body and each vertex's nearest face is the one it approaches, out
// to the voxel size plus the two largest distances a body's surface moved in the first solve
// (x0 to freeEnd): every vertex that could reach a face of another body within the step. (Found
// at the end of the first solve, within the voxel size, a vertex that moved deeper than that
// into the other body had no constraint: two balls closing at 1 m/s ended steps a voxel inside
// each other, and at 10 m/s passed through each other.)
std::vector<PairConstraint> World::stepBodyPairs(const std::vector<Vec3>& x0, const std::vector<Vec3>& freeEnd,
                                                 std::vector<uint64_t>& keys) {
  Real first = 0, second = 0;
  for (const ContactBody& b : bodyContacts_->bodies()) {
    Real moved = 0;
    for (uint32_t u : b.vertices) moved = std::max(moved, (freeEnd[u] - x0[u]).norm());
    if (moved > first)
      second = first, first = moved;
    else
      second = std::max(second, moved);
  }
  return bodyPairConstraints(x0, bodyContactMargin() + first + second, keys);
}

// The second solve, from the step's start, with the held vertices and the pair constraints.
// Contact forces: the held solve's multipliers (the force holding each vertex, times dt) are the
// impulse the contacts give the body, each on the surface that moved it; the last contact pass
// adds its own velocity changes. The first pass's are dropped with its state.
void World::solveHeld(const State& start, const std::vector<Vec3>& targets, const HeldContacts& held,
                      std::vector<PairConstraint>& pairs) {
  StepContext& c = *scratch_;
  c.impulse.assign(manipulators_.size() + kWalls, ContactForce{});
  c.work = 0;
  state_.positions = start.positions, state_.velocities = start.velocities, state_.rotations = start.rotations;
  std::vector<Vec3> heldForces;
  projective_->step(state_.positions, state_.velocities, state_.rotations, c.gravity, sim_.damping,
                    sim_.implicitIterations, targets, sim_.rotationIterations, held.vertices, held.at, held.normal,
                    &heldForces, &pairs, held.friction, held.letGo, held.slip);
  for (size_t j = 0; j < held.vertices.size(); ++j) {
    const size_t k = size_t(std::max(0, held.surface[j]));
    const Vec3 centre = k < manipulators_.size() ? manipulators_[k].position : Vec3::Zero();
    addImpulse(c.impulse[k], heldForces[j] * dt_, held.at[j], centre);
    // The contacts' work (contact_work.h): the hold's impulse times its surface's velocity, so
    // a manipulator that presses a body into a wall at a frame-size step supplies the energy
    // the press stores (a fixed wall none).
    if (k < manipulators_.size())
      c.work += heldForces[j].dot(manipulators_[k].position - manipulators_[k].previousPosition);
  }
}

// The end of an implicit or large step: deepest contact, manipulators' sweep start, time, pins
// (the force ledger closes in World::step, after the body contacts).
void World::finishFrameStep(Real tNext) {
  scratch_->maxContactDepth = scratch_->contactDepth.empty()
                                  ? 0
                                  : *std::max_element(scratch_->contactDepth.begin(), scratch_->contactDepth.end());
  for (Manipulator& m : manipulators_) m.previousPosition = m.position;
  state_.time = tNext;
  if (!pinSet_.empty()) applyPins(state_.time);
}

}  // namespace gradel
