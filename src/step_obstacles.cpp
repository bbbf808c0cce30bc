// The obstacles' stage: contacts of vertices with the manipulators and the walls (contacts.h,
// per vertex), the sweep of fast manipulators along their paths, the manipulators' poses, and
// the step's force ledger (ContactForces, contact work).
#include <algorithm>
#include <array>
#include <cmath>

#include "gradel/contact_work.h"
#include "step_context.h"

namespace gradel {

// Contacts of one vertex, swept from `previous` (independent per vertex); `previousVelocity` is its
// velocity at the start of the step (the bounce uses the speed at which it crossed a surface, not
// the speed gained inside it: contacts.h). The first pass bounces (sec. 3.5). A vertex pinched
// between surfaces (a manipulator and a wall, or two manipulators) is
// resolved again, up to three more passes, inelastically: repeated elastic reflections between
// two surfaces would pump energy into it. The walls go last in every pass, so no vertex ever
// leaves the box. Returns the deepest penetration found [m].
// `impulse` (one entry per manipulator, then the walls) gets the vertex's impulse m dv from each
// surface and its moment (contact forces); `surface`, when given, the last surface that moved it.
Real World::resolveVertexContacts(const Vec3& previous, const Vec3& previousVelocity, Vec3& x, Vec3& v, Real mass,
                                  Real stiffness, ContactForce* impulse, Real* work, int* surface) const {
  const int dim = model_->dim;
  const Vec3 xFree = x;
  const StepStart start{previousVelocity, dt_, sim_.integrator == IntegratorKind::SymplecticEuler};
  const size_t surfaces = manipulators_.size() + (domain_.enabled ? 1 : 0);
  const size_t K = manipulators_.size();
  Real depth = 0;
  // The contacts' work (contact_work.h): J . u per surface, and how far the surfaces that moved
  // the vertex moved themselves.
  Real w = 0, travel = 0;
  for (int pass = 0; pass < 4; ++pass) {
    const bool bounce = pass == 0;
    Real passDepth = 0;
    for (size_t k = 0; k < K; ++k) {
      const Vec3 before = v;
      const Manipulator& mp = manipulators_[k];
      const Real d = resolveManipulator(mp, previous, x, v, bounce, &start).depth;
      if (d > 0 || v != before) {
        addImpulse(impulse[k], mass * (v - before), x, mp.position);
        // A manipulator growing back from a start overlap (overlaps.h) moves its surface outwards too.
        Vec3 u = mp.velocity;
        const Real growth = k < manipulatorGrowth_.size() ? manipulatorGrowth_[k] : 0;
        if (growth > 0 && (x - mp.position).norm() > 0) u += growth * (x - mp.position).normalized();
        w += mass * (v - before).dot(u), travel = std::max(travel, u.norm() * dt_);
      }
      if (d > 0 && surface) *surface = int(k);
      passDepth = std::max(passDepth, d);
    }
    Vec3 wallDv[kWalls] = {Vec3::Zero(), Vec3::Zero(), Vec3::Zero(), Vec3::Zero(), Vec3::Zero(), Vec3::Zero()};
    const ContactResult r = resolveDomain(domain_, previous, x, v, dim, bounce, &start, wallDv);
    const Real d = r.depth;
    for (int wall = 0; wall < kWalls; ++wall)
      if (wallDv[wall] != Vec3::Zero()) {
        addImpulse(impulse[K + size_t(wall)], mass * wallDv[wall], x, Vec3::Zero());
        w += mass * wallDv[wall].dot(wallVelocity_[size_t(wall)]);
        travel = std::max(travel, wallVelocity_[size_t(wall)].norm() * dt_);
      }
    if (d > 0 && surface) *surface = int(K) + r.wall;
    passDepth = std::max(passDepth, d);
    depth = std::max(depth, passDepth);
    if (passDepth == 0 || surfaces < 2) break;
  }
  if (work && depth > 0) w += displacementWork(stiffness, previous, xFree, x, travel);
  if (work) *work += w;
  return depth;
}

// Contacts of every vertex from scratch_->previousPositions (the implicit step).
void World::stageContacts(size_t begin, size_t end) {
  scratch_->contactSurface.resize(model_->numVertices());
  for (size_t i = begin; i < end; ++i) {
    scratch_->contactSurface[i] = -1;
    scratch_->contactDepth[i] = resolveVertexContacts(scratch_->previousPositions[i], scratch_->previousVelocities[i],
                                                      state_.positions[i], state_.velocities[i], model_->mass[i],
                                                      vertexStiffness_[i], scratch_->impulse.data(), &scratch_->work,
                                                      &scratch_->contactSurface[i]);
  }
}

// Contact forces: every step starts with zero impulses on every surface ...
void World::beginContactImpulses() {
  const size_t surfaces = manipulators_.size() + kWalls;
  scratch_->impulse.assign(surfaces, ContactForce{});
  for (StepContext::TouchedBlocks& list : scratch_->touched) list.block.clear(), list.work.clear(), list.impulse.clear();
  scratch_->work = 0;
}

// ... and ends with the explicit stage's blocks added in block order (the same sums at any
// thread count), the step's forces (the impulse on the body, negated, over dt) and the average.
void World::finishContactImpulses() {
  const size_t K = manipulators_.size(), surfaces = K + kWalls;
  std::vector<ContactForce>& J = scratch_->impulse;
  // The touched blocks of every member, in block order (each block was handled by one member).
  std::vector<std::array<uint32_t, 3>> order;  // block, member, index in the member's list
  for (size_t t = 0; t < scratch_->touched.size(); ++t)
    for (size_t k = 0; k < scratch_->touched[t].block.size(); ++k)
      order.push_back({scratch_->touched[t].block[k], uint32_t(t), uint32_t(k)});
  std::sort(order.begin(), order.end());
  for (const auto& [block, t, k] : order) {
    const StepContext::TouchedBlocks& list = scratch_->touched[t];
    scratch_->work += list.work[k];
    for (size_t s = 0; s < surfaces; ++s)
      J[s].force += list.impulse[k * surfaces + s].force, J[s].torque += list.impulse[k * surfaces + s].torque;
  }
  stepForces_.manipulators.resize(K);
  averageImpulse_.manipulators.resize(K);
  // The walls together: their impulses summed in wall order (each the same at any thread count).
  ContactForce allWalls;
  for (size_t w = 0; w < size_t(kWalls); ++w) allWalls.force += J[K + w].force, allWalls.torque += J[K + w].torque;
  for (size_t s = 0; s <= surfaces; ++s) {
    const ContactForce& j = s < surfaces ? J[s] : allWalls;
    ContactForce& f = s < K ? stepForces_.manipulators[s] : s < surfaces ? stepForces_.wall[s - K] : stepForces_.walls;
    ContactForce& a = s < K          ? averageImpulse_.manipulators[s]
                      : s < surfaces ? averageImpulse_.wall[s - K]
                                     : averageImpulse_.walls;
    f.force = -j.force / dt_, f.torque = -j.torque / dt_;
    a.force -= j.force, a.torque -= j.torque;
  }
  averageTime_ += dt_;
  // The steps' positive totals: a step whose contacts took energy out gives none back to the
  // budget (the walls' restitution would otherwise hide what a later step supplies).
  if (std::isfinite(scratch_->work)) contactWork_ += std::max(Real(0), scratch_->work);
}

ContactForces World::averageContactForces() const {
  ContactForces f = averageImpulse_;
  f.manipulators.resize(manipulators_.size());
  const Real s = averageTime_ > 0 ? 1 / averageTime_ : 0;
  for (ContactForce& c : f.manipulators) c.force *= s, c.torque *= s;
  f.walls.force *= s, f.walls.torque *= s;
  for (ContactForce& c : f.wall) c.force *= s, c.torque *= s;
  return f;
}

void World::restartForceAverage() {
  averageImpulse_ = ContactForces{};
  averageImpulse_.manipulators.resize(manipulators_.size());
  averageTime_ = 0;
}

void World::moveManipulators(Real tNext) {
  for (Manipulator& m : manipulators_) {
    if (m.settings.path.keys.empty()) continue;  // posed from outside
    m.position = m.settings.path.position(tNext);
    m.velocity = m.settings.path.velocity(tNext);
  }
}

// A manipulator that moves more than its size within the step could cross the body between
// the step's two poses (a strike at 100 m/s moves 1.7 m in 1/60 s): its scripted path is swept
// in sub-intervals of at most its size (up to 256), each vertex moving along its step,
// straight, until a sub-interval's swept contact test (resolveManipulator) hits it; from then on
// it flies with the velocity the contact gave it: the manipulator's normal velocity at that
// time (the velocity rule with restitution 0; friction as the contact pass's), so that it rides
// on the manipulator's surface and the held solve (step_implicit.cpp), which holds it there,
// hands the hit to the whole body: the body's elements take the momentum exchange and give the
// bounce back. Reflected by the manipulator's restitution, as a free particle, each vertex the
// strike reached flew ahead of the striker at up to twice its speed and dragged the body after
// it (issue 26 item 1: the strike scene at E = 1e5 Pa and dt = 1/30 s peaked at 1.60x the
// explicit run's kinetic + elastic energy, the ball leaving at ~1.2 m/s against the striker's
// 1.25 m/s; now 0.82x, as the unswept holds at 1/60 s, 0.56x). A vertex that was hit is marked
// so that the contact stage does not sweep the whole step again for it (its start is moved
// with the manipulator).
void World::sweepManipulatorPaths(Real t0) {
  const RestModel& m = *model_;
  const size_t V = m.numVertices();
  for (const Manipulator& mp : manipulators_) {
    const Path& path = mp.settings.path;
    if (path.keys.empty() || mp.settings.shape == ManipulatorShape::Blade) continue;  // a blade never pushes
    const Real size = mp.settings.shape == ManipulatorShape::Cylinder
                          ? std::min(mp.settings.radius, mp.settings.halfLength)
                          : mp.settings.radius;
    constexpr int kProbe = 16, kMaxSub = 256;
    Real length = 0;
    for (int k = 1; k <= kProbe; ++k)
      length += (path.position(t0 + dt_ * k / kProbe) - path.position(t0 + dt_ * (k - 1) / kProbe)).norm();
    const int K = std::min(kMaxSub, int(std::ceil(length / size)));
    if (K <= 1) continue;
    std::vector<Vec3> centre(size_t(K) + 1), velocity(size_t(K) + 1);
    for (int k = 0; k <= K; ++k) centre[size_t(k)] = path.position(t0 + dt_ * k / K);
    // Each sub-interval's mean velocity: a strike that ends within a sub-interval still hits at its speed.
    for (int k = 1; k <= K; ++k) velocity[size_t(k)] = (centre[size_t(k)] - centre[size_t(k) - 1]) * (K / dt_);
    Manipulator sub;
    sub.settings.shape = mp.settings.shape, sub.settings.radius = mp.settings.radius;
    sub.settings.halfLength = mp.settings.halfLength, sub.settings.axis = mp.settings.axis;
    sub.settings.restitution = mp.settings.restitution, sub.settings.friction = mp.settings.friction;
    const Real h = dt_ / K;
    for (size_t i = 0; i < V; ++i) {
      const Vec3 xs = scratch_->previousPositions[i], xe = state_.positions[i];
      Vec3 x = xs, v = scratch_->previousVelocities[i];
      Real depth = 0;
      for (int k = 1; k <= K; ++k) {
        sub.previousPosition = centre[size_t(k) - 1], sub.position = centre[size_t(k)],
        sub.velocity = velocity[size_t(k)];
        Vec3 xk = depth > 0 ? Vec3(x + h * v) : Vec3(xs + (xe - xs) * (Real(k) / K));
        Vec3 vk = depth > 0 ? v : state_.velocities[i];
        const StepStart start{v, h};
        const Real d = resolveManipulator(sub, x, xk, vk, /*bounce=*/false, &start).depth;
        if (d > 0 || depth > 0) v = vk;
        depth = std::max(depth, d);
        x = xk;
      }
      if (depth == 0) continue;
      // Contact forces: the velocity the sweep gave the vertex, against the one it ended the solve with.
      addImpulse(scratch_->impulse[size_t(&mp - manipulators_.data())], m.mass[i] * (v - state_.velocities[i]), x,
                 mp.position);
      scratch_->work += m.mass[i] * (v - state_.velocities[i]).dot((mp.position - mp.previousPosition) / dt_);
      state_.positions[i] = x, state_.velocities[i] = v;
      scratch_->previousPositions[i] = x - (mp.position - mp.previousPosition);
      scratch_->contactDepth[i] = std::max(scratch_->contactDepth[i], depth);
    }
  }
}

}  // namespace gradel
