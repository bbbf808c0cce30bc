// The energy contacts put into the bodies (the divergence guard's "supplied by the contacts",
// divergence.h). A wall or a kinematic manipulator moves a vertex (the projection out of the
// surface) and changes its velocity (the bounce, friction); both can add energy that no
// numerical error made: a tool placed inside a body, or driven through it at 1000 m/s, stores
// elastic energy by pushing the material aside. Per vertex and contact resolution, from the
// vertex before (xFree, vFree: where the step's forces took it) and after the contacts (x, v):
//   W = 1/2 m (|v|^2 - |vFree|^2)           kinetic energy the contact gave (signed)
//     - m a . (x - xFree)                   work against the force that pressed the vertex in,
//                                           a = (vFree - v0) / dt (first order; signed)
//     + 1/2 k_i max(0, |x - xFree| - |xFree - x0|)^2
// The last term is the elastic energy of a displacement the vertex's own motion does not
// explain (a surface that moved into it or started inside it), with k_i the sum of the
// stiffnesses of the vertex's elements (all other vertices held: an upper bound of what moving
// it alone stores). A vertex that flew into a static surface is put back along at most its own
// step and adds nothing there. The world sums W over the step's vertices (in a fixed order)
// and keeps the running sum of the steps' positive totals (World::contactWork()).
#pragma once

#include <vector>

#include "gradel/model.h"
#include "gradel/types.h"

namespace gradel {

/// W above [J] for one vertex: mass m [kg], stiffness k [N/m], x0 / v0 its start of the step,
/// (xFree, vFree) its state before the contacts, (x, v) after them, dt [s] > 0.
Real contactVertexWork(Real m, Real k, const Vec3& x0, const Vec3& v0, const Vec3& xFree, const Vec3& vFree,
                       const Vec3& x, const Vec3& v, Real dt);

/// k_i per vertex [N/m]: the sum of k_e over the elements the vertex belongs to.
std::vector<Real> vertexStiffness(const RestModel& model);

}  // namespace gradel
