// The response's kernels (body contacts): a contact's vertex against the point of its face at
// barycentric weights w, corrected together so that the sum of m dx is zero.
#pragma once

#include "gradel/body_contacts.h"

namespace gradel {
namespace {

// Generalised inverse mass of a contact: vertex plus the face's point with weights w.
[[maybe_unused]] Real contactInvMass(const BodyContacts::Contact& c, const Real* im) {
  return im[c.vertex] + c.w[0] * c.w[0] * im[c.face[0]] + c.w[1] * c.w[1] * im[c.face[1]] +
         c.w[2] * c.w[2] * im[c.face[2]];
}

// Applies the impulse-like change j along a direction d (per unit generalised mass): the vertex
// moves by im_p j d, the face's corners by -w_k im_k j d. Used for positions and velocities.
[[maybe_unused]] void applyPair(const BodyContacts::Contact& c, const Real* im, Vec3* y, const Vec3& jd) {
  y[c.vertex] += im[c.vertex] * jd;
  for (int k = 0; k < 3; ++k) y[c.face[size_t(k)]] -= c.w[size_t(k)] * im[c.face[size_t(k)]] * jd;
}

[[maybe_unused]] Vec3 relative(const BodyContacts::Contact& c, const Vec3* y) {
  return y[c.vertex] - (c.w[0] * y[c.face[0]] + c.w[1] * y[c.face[1]] + c.w[2] * y[c.face[2]]);
}

// How far [m] the contact's vertex lay behind its plane (the normal as found, at its face point)
// at positions y, e.g. the step's start; negative in front of it.
[[maybe_unused]] Real depthBehind(const BodyContacts::Contact& c, const Vec3* y) { return -c.n.dot(relative(c, y)); }

}  // namespace
}  // namespace gradel
