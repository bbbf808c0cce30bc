// Time integration of one vertex (paper sec. 2.3, eqs. 2-3): pure functions of a position x, a
// velocity v and an acceleration a over one step dt, with velocity damping. World's vertex stage
// calls them for every vertex (src/step_explicit.cpp, stageVertices), right after gathering the elastic
// force. They are templates over the vector type (Vec3, or the vertex stage's 4-wide register)
// and header-inline so that the hot loop compiles to exactly these expressions.
#pragma once

#include "gradel/types.h"

namespace gradel {

/// The velocity factor of damping rate c [1/s] over a step dt [s]: v <- v / (1 + c dt). In (0, 1]
/// for c, dt >= 0: damping never adds energy.
inline Real dampingFactor(Real damping, Real dt) { return 1.0 / (1.0 + damping * dt); }

/// Symplectic Euler (the default): V(T+dT) = (V(T) + A(T) dT) damp, then
/// P(T+dT) = P(T) + V(T+dT) dT. Exact for a constant acceleration at the step points up to the
/// half-step offset of its velocity; bounded energy on an oscillation with omega dt < 2.
template <class V>
inline void symplecticEulerStep(V& x, V& v, const V& a, Real dt, Real damp) {
  v = (v + dt * a) * damp;
  x = x + dt * v;  // P(T+dT) = P(T) + V(T+dT) dT
}

/// Forward Euler, the paper's literal eq. 3: P(T+dT) = P(T) + V(T) dT, then
/// V(T+dT) = (V(T) + A(T) dT) damp. Gains energy on every undamped oscillation.
template <class V>
inline void forwardEulerStep(V& x, V& v, const V& a, Real dt, Real damp) {
  x = x + dt * v;  // eq. 3 with V(T): the paper's literal order
  v = (v + dt * a) * damp;
}

/// The free-flight prediction x + dt v + c dt^2 g: c = 1/2 where a vertex lands after dt under
/// gravity alone (the large step's and the body contacts' broad phases), c = 1 the inertial
/// target of backward Euler (projective.h) and of the large step's half steps (large_step.h).
inline Vec3 freeFlight(const Vec3& x, const Vec3& v, Real dt, Real c, const Vec3& g) {
  return x + dt * v + c * dt * dt * g;
}

}  // namespace gradel
