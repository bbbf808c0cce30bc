// The body-contact stage's last resort: "inside" findings no step can reach dropped
// (dropUnreachable), and bodies still deep in each other after every round taken back towards
// where they started the step (takeBack). docs/speed.md, "Body contacts: the stage".
#include <cmath>
#include <vector>

#include "body_contact_kernels.h"
#include "gradel/body_contacts.h"

namespace gradel {

// The pseudo-normal test reads "inside" off the faces around the nearest feature, which is only
// right where the surface near it is not folded. A soft body crushed by a stiffer one folds its
// surface (elements at a third of their volume), and there a vertex that never came near was read
// inside by up to a voxel: pushed out along a far face, it set the bodies ringing (a stiff 9^3 ball
// at 1.45 m/s into a soft 6^3 one: energy x1.8 in one step, then x28 once the last resort took the
// bodies back over such "contacts"). A contact deeper than the vertex and the other body's surface
// can have come towards each other in the step (plus what a step may leave: kTakeBackDepth) cannot
// be from a vertex that was outside at the step's start; such a one is asked of the winding number
// of the other body's closed surface (exact, O(faces), rare) and dropped when that says outside.
// Explicit steps only (s.leapfrog: a step moves a surface a fraction of a voxel): where a frame-size
// step crushed a ball to half its size within the step, its surface folds through itself and the
// winding number is no better a judge than the pseudo-normal (two balls at 10 m/s each, dt = 1/60 s:
// dropping such findings left one more step with a vertex inside).
void BodyContacts::dropUnreachable(const BodyContactState& s, BodyContactStats& stats) {
  const Vec3* x0 = s.previousPositions;
  if (!x0 || !s.leapfrog) return;
  const Vec3* x = s.positions;
  size_t kept = 0;
  for (size_t k = 0; k < round_.size(); ++k) {
    const Contact& c = round_[k];
    const Real allowed = allowedDepth(c, s);
    if (allowed > 0 && !(c.depth > allowed)) continue;  // a misread fold no deeper than at the start (addContacts)
    const uint32_t b = bodyOf_[c.face[0]];
    const Real reach = (x[c.vertex] - x0[c.vertex]).norm() + moved_[b] + kTakeBackDepth * bodies_[b].thickness + skin_;
    bool keep = !(c.depth > reach);
    if (!keep) ++stats.windingNumbers, keep = !(std::abs(windingNumber(x[c.vertex], bodies_[b].triangles, x)) < 0.5);
    if (keep) {
      round_[kept++] = c;
    } else {
      ++stats.unreachable;
    }
  }
  round_.resize(kept);
}

// The last resort (header): while a vertex is inside deeper than kTakeBackDepth of a voxel, the
// bodies of the contacts go back along the straight line from where they ended towards where they
// started, all by one fraction, positions and velocities alike (the taken-back bodies make that
// fraction of the step; keeping the step's velocities while taking the positions back let the
// elastic forces of a pressed pair accelerate the bodies step after step without moving them: two
// balls at 4 m/s, energy x1e5). Shallower leftovers are pushed out once more and kept as contacts.
void BodyContacts::takeBack(const BodyContactState& s, BodyContactStats& stats) {
  if (!detectAll(s, stats)) return;
  Vec3* x = s.positions;
  Vec3* v = s.velocities;
  const Vec3* x0 = s.previousPositions;
  const Vec3* v0 = s.previousVelocities;
  const Real* im = s.invMass;
  const size_t B = bodies_.size();
  // Deeper than the tolerance, for the contacts of round_ now; beyond: deeper than the tolerance
  // beyond where the vertex lay behind the same point of the face (along the same normal) at the
  // step's start.
  auto deep = [&](bool beyond) {
    for (const Contact& c : round_) {
      const Real atStart = beyond ? std::max(Real(0), depthBehind(c, x0)) : Real(0);
      if (c.depth > kTakeBackDepth * bodies_[bodyOf_[c.face[0]]].thickness + atStart) return true;
    }
    return false;
  };
  std::vector<uint8_t> back(B, 0);
  std::vector<std::vector<Vec3>> end(B), endV(B);  // a body's positions and velocities when it joined
  Real f = 1;
  // In an explicit step (s.leapfrog) only a depth gained in the step counts: a vertex already about
  // as deep behind the same face point at the step's start cannot be helped by taking the step
  // back (where elements inverted, the sign test read a vertex outside at the start and 0.44 voxel
  // inside after 1/16 of the step: it had moved 0.014 voxel, and the winding number said inside at
  // both); what is left is pushed out below (a misread fold only partly: addContacts). Taking such pairs back
  // (to 1/16 of the step, then to its start) froze them: two 16^3 balls at 10 m/s, generic build,
  // 2,234 of 2,424 steps taken back; with a fit rounded differently, 889 of 970 and energy x10 at
  // dt_fraction 0.25 (docs/speed.md, "Violent hits"). After a frame-size step every deep vertex
  // counts: 1/16 of it let two balls at 10 m/s pass through each other (the large step, dt = 1/60 s).
  while (deep(s.leapfrog)) {
    bool grew = false;
    for (const Contact& c : round_)
      for (const size_t b : {size_t(bodyOf_[c.vertex]), size_t(bodyOf_[c.face[0]])})  // (both on a surface)
        if (b < B && !back[b]) {
          back[b] = 1, grew = true;
          end[b].assign(x + bodies_[b].vertexBegin, x + bodies_[b].vertexEnd);
          endV[b].assign(v + bodies_[b].vertexBegin, v + bodies_[b].vertexEnd);
        }
    if (f == 0 && !grew) break;  // nothing left to take back (pinned vertices stay)
    f = f > kTakeBackLeast ? f / 2 : 0;
    for (size_t b = 0; b < B; ++b) {
      if (!back[b]) continue;
      const uint32_t begin = bodies_[b].vertexBegin;
      for (uint32_t u = begin; u < bodies_[b].vertexEnd; ++u) {
        if (im[u] == 0) continue;
        x[u] = x0[u] + f * (end[b][u - begin] - x0[u]);
        if (v0) v[u] = v0[u] + f * (endV[b][u - begin] - v0[u]);
      }
    }
    ++stats.takeBacks;
    if (!detectAll(s, stats)) break;
  }
  stats.takenBackTo = f;
  if (round_.empty()) return;
  // What is left is shallow (or could not be taken back: pinned): out once more, as a round's contacts.
  const size_t first = contacts_.size();
  addContacts(s);
  for (int it = 0; it < kIterations; ++it)
    for (size_t k = first; k < contacts_.size(); ++k) {
      const Contact& c = contacts_[k];
      const Real W = contactInvMass(c, im);
      const Real gap = c.n.dot(relative(c, x)) - skin_ + keep_[k];
      if (W > 0 && gap < 0) applyPair(c, im, x, (-gap / W) * c.n);
    }
}

}  // namespace gradel
