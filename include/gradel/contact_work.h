// The energy contacts put into the bodies (the divergence guard's "supplied by the contacts",
// divergence.h). A contact never adds energy in the frame of the surface it resolves (contacts.h),
// so in the world frame it adds at most the work of the surface's motion: with J = m dv the
// impulse it gave a vertex and u the surface's velocity there,
//   W = J . u                                        (a static wall: 0)
// A manipulator driven through a body at 1000 m/s, two cylinders crushing it, a wall or a tool
// pushing a start overlap out (overlaps.h: they move at 1 m/s) all supply W. A surface that
// appears inside a body without moving there (a tool posed inside it from outside, a pose jump)
// moves vertices farther than their own step and the surface's motion explain; that displacement
// d stores elastic energy, counted as
//   + 1/2 k_i d^2,  d = max(0, |x - xFree| - |xFree - x0| - |u| dt)
// with k_i the sum of the stiffnesses of the vertex's elements (all other vertices held: an
// upper bound of what moving it alone stores). The world sums W over the step's vertices (in a
// fixed order) and keeps the running sum of the steps' positive totals (World::contactWork()).
// A body that diverges on a static floor gets nothing from it: exit 3 still means divergence.
#pragma once

#include <vector>

#include "gradel/model.h"
#include "gradel/types.h"

namespace gradel {

/// 1/2 k d^2 above [J]: stiffness k [N/m], x0 the vertex's start of the step, xFree where the
/// step's forces took it, x where the contacts put it, surfaceTravel [m] how far the surface
/// that moved it moved within the step (|u| dt).
Real displacementWork(Real k, const Vec3& x0, const Vec3& xFree, const Vec3& x, Real surfaceTravel);

/// k_i per vertex [N/m]: the sum of k_e over the elements the vertex belongs to.
std::vector<Real> vertexStiffness(const RestModel& model);

}  // namespace gradel
