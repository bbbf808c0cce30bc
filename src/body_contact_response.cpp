// Response of the body-contact stage: the positions pushed apart along the normal (Gauss-Seidel,
// split by inverse mass, friction undoing the step's slip), then equal and opposite impulses on
// the relative velocity (restitution, Coulomb friction) that never add kinetic energy (issue 26,
// contacts.h's rules). docs/speed.md, "Body contacts: the stage".
#include <algorithm>
#include <cmath>

#include "body_contact_kernels.h"
#include "body_contact_tuning.h"
#include "gradel/body_contacts.h"
#include "gradel/triangle_queries.h"

namespace gradel {

// Appends round_ to contacts_ with each one's keep_. In an explicit step (s.leapfrog), a finding
// whose vertex lay behind the same face point, along the same normal, by d0 > kTakeBackDepth
// voxels at the step's start while the winding number of the other body's surface says it was
// outside then, is a misreading of a folded or crushed surface (the pseudo-normal test reads the
// wrong side there): its vertex may end the step up to d0 - kDepenetration voxels behind that
// plane, and a finding no deeper is dropped (dropUnreachable). Pushing such vertices out along
// far faces took the energy of a stiff 6^3 ball into a soft one to 1.35x, grew a violent hit's
// search radius round by round (21 M nearest-point tests in a step) and froze pairs in the last
// resort. Every other contact (outside at the start, or inside by the winding number too) keeps
// nothing: the same arithmetic as before, and no vertex is left inside another body by it.
Real BodyContacts::allowedDepth(const Contact& c, const BodyContactState& s) const {
  const Vec3* x0 = s.previousPositions;
  if (!x0 || !s.leapfrog) return 0;
  const uint32_t u = c.vertex, b = bodyOf_[c.face[0]];
  const Real h = bodies_[b].thickness;
  // The depth behind the face's plane at the step's start, where the face was then.
  const Real atStart = depthBehind(c, x0);
  if (!(atStart > kTakeBackDepth * h)) return 0;
  if (startAskedStage_[u] != stage_ || startAskedBody_[u] != b) {  // once per vertex, body and stage
    startAskedStage_[u] = stage_, startAskedBody_[u] = b;
    startInside_[u] = std::abs(windingNumber(x0[u], bodies_[b].triangles, x0)) >= 0.5, ++startWindings_;
  }
  if (startInside_[u]) return 0;
  // The premise (the pseudo-normal misreads a fold) fails where the winding number puts the vertex
  // inside now too: then it is pushed out as any other (two 8-voxel balls head on at 0.5 m/s: a
  // vertex sliding onto a face was 1 mm behind its plane at the start, outside, and was allowed to
  // end the step 9.6 um inside the other ball).
  ++startWindings_;
  if (std::abs(windingNumber(s.positions[u], bodies_[b].triangles, s.positions)) >= 0.5) return 0;
  return atStart - kDepenetration * h;
}

void BodyContacts::addContacts(const BodyContactState& s) {
  for (const Contact& c : round_) keep_.push_back(std::min(allowedDepth(c, s), c.depth));
  contacts_.insert(contacts_.end(), round_.begin(), round_.end());
}

// Still inside after every round: contacts that contradict each other (two vertices each
// inside the other body behind faces they are corners of, where coarse staircases cross).
// Each such vertex and its face point go back to where they were relative to each other at
// the start of the step, when the vertex was outside (split by inverse mass, as the projections).
void BodyContacts::returnToStart(const BodyContactState& s) {
  Vec3* x = s.positions;
  const Real* im = s.invMass;
  for (const Contact& c : round_) markTouched(c, x, s.velocities);
  for (int it = 0; it < kIterations; ++it)
    for (const Contact& c : round_) {
      const Real W = contactInvMass(c, im);
      if (W > 0) applyPair(c, im, x, (relative(c, s.previousPositions) - relative(c, x)) / W);
    }
  addContacts(s);
}

// Positions, Gauss-Seidel over every contact found so far (a later round's contacts and an
// earlier round's act together): out to the skin along n, split by inverse mass; friction
// undoes the tangential slip of the step up to friction x depth (once, when first found).
void BodyContacts::projectPositions(const BodyContactState& s) {
  Vec3* x = s.positions;
  const Real* im = s.invMass;
  const size_t first = contacts_.size();
  addContacts(s);
  for (const Contact& c : round_) markTouched(c, x, s.velocities);
  // kIterations sweeps, then more (up to kMaxIterations) while a sweep still found a vertex
  // behind its contact point along the normal (gap < -skin: n . (p - c) < 0): where contacts
  // share vertices (a corner pushed by the vertices around it) each sweep undoes part of the
  // one before, and what a round leaves the next finds again (two 64^3 balls pressed together,
  // 400 steps: 1,413 lookups a step against 1,555 with 4 sweeps; docs/speed.md).
  for (int it = 0; it < kMaxIterations; ++it) {
    bool inside = false;
    for (size_t k = 0; k < contacts_.size(); ++k) {
      const Contact& c = contacts_[k];
      const Real W = contactInvMass(c, im);
      if (!(W > 0)) continue;
      const Real gap = c.n.dot(relative(c, x)) - skin_ + keep_[k];
      if (gap >= 0) continue;
      inside = inside || gap < -skin_;
      applyPair(c, im, x, (-gap / W) * c.n);
      if (it == 0 && k >= first && settings_.friction > 0) {
        Vec3 slip = relative(c, x) - relative(c, s.previousPositions);
        slip -= slip.dot(c.n) * c.n;
        const Real len = slip.norm(), allowed = settings_.friction * -gap;
        if (len > 0) applyPair(c, im, x, (-(len <= allowed ? Real(1) : allowed / len) / W) * slip);
      }
    }
    if (it + 1 >= kIterations && !inside) break;
  }
}

// Velocities: equal and opposite impulses on the relative velocity at each contact, never adding
// kinetic energy (the manipulators' rules, contacts.h). With symplectic Euler the stored velocity
// is half a step behind the positions: the relative velocity at their time is w = rel + a dt / 2,
// a dt the step's change of the contact's relative velocity (from the velocities the response
// started with: entry_); the impulses act on w. An impulse that takes the normal part of w from
// wn < 0 to wn' with |wn'| <= |wn| and shrinks the tangential part changes the kinetic energy by
// (|w'|^2 - |w|^2) / (2 W) <= 0, whatever the other contacts on the same vertices did before it.
void BodyContacts::applyImpulses(const BodyContactState& s) {
  Vec3* v = s.velocities;
  const Real* im = s.invMass;
  const Real e = settings_.restitution, mu = settings_.friction;
  const Vec3* v0 = s.previousVelocities;
  const bool leap = s.leapfrog && v0;
  const bool timed = v0 && s.dt > 0;
  entry_.resize(contacts_.size());
  for (size_t k = 0; k < contacts_.size(); ++k) entry_[k] = relative(contacts_[k], v);
  for (size_t k = 0; k < contacts_.size(); ++k) {
    const Contact& c = contacts_[k];
    const Real W = contactInvMass(c, im);
    if (!(W > 0)) continue;
    const Vec3 start = v0 ? relative(c, v0) : entry_[k];
    const Vec3 half = leap ? Vec3(0.5 * (entry_[k] - start)) : Vec3::Zero();  // a dt / 2
    const Vec3 w = relative(c, v) + half;
    const Real wn = w.dot(c.n);
    if (!(wn < 0)) continue;  // receding at the time of the positions: its next step takes it out
    // The bounce: restitution times the speed at which the contact approached at the start of the
    // step, never more than it has now; nothing for one that was resting or receding then (rule 1).
    const Real u0 = start.dot(c.n);
    Real out = u0 < 0 ? e * std::min(-u0, -wn) : Real(0);
    // The elastic energy the position projection stored (rule 2): pushed apart by `depth` along n
    // against the relative acceleration an < 0 that pressed the vertex in, -an depth per unit of
    // generalised mass 1 / W; taken out of the bounce, then out of the sliding.
    Real stored = timed ? std::max(Real(0), -(entry_[k] - start).dot(c.n) / s.dt) * (c.depth - keep_[k]) : Real(0);
    const Real fromBounce = std::min(stored, Real(0.5) * out * out);
    out = std::sqrt(std::max(Real(0), out * out - 2 * fromBounce));
    stored -= fromBounce;
    const Real jn = (out - wn) / W;
    Vec3 wt = w - wn * c.n;
    const Real wtLen = wt.norm();
    Vec3 dv = (out - wn) * c.n;  // the change of the relative velocity
    if (wtLen > 0 && (mu > 0 || stored > 0)) {
      // Coulomb: the tangential impulse at most mu times the normal one; then the stored energy.
      Real keep = std::max(Real(0), wtLen - mu * jn * W);
      if (stored > 0) keep = std::sqrt(std::max(Real(0), keep * keep - 2 * stored));
      dv += ((keep - wtLen) / wtLen) * wt;
    }
    applyPair(c, im, v, dv / W);
  }
}

}  // namespace gradel
