// External forces on vertices (a push from a script, PyBullet's applyExternalForce): a force F_i
// [N] per vertex that acts during a step. Every integrator gets it the same way, as the impulse
// F_i dt on the vertex's velocity at the start of the step, before the integrator runs:
//   symplectic Euler   v += dt (f + F) / m: exactly a force term of eq. 2;
//   forward Euler      the position update sees the kicked velocity (dt^2 F / m more);
//   implicit / large   the inertial prediction x + dt v gets dt^2 F / m, the momentum F dt.
// A pinned vertex ignores it (its pin prescribes it). The impulse changes the bodies' momentum by
// sum F dt (World::externalImpulse()); the energy it gives them, the kinetic energy the kicks add,
// is counted by the divergence guard as supplied (World::externalWork(), divergence.h).
#pragma once

#include <vector>

#include "gradel/types.h"

namespace gradel {

/// What one step's external impulses gave the bodies.
struct ExternalImpulse {
  Vec3 impulse{0, 0, 0};  ///< [N s] sum of F_i dt over the vertices it acted on.
  Real work = 0;          ///< [J] the kinetic energy the kicks added (may be < 0: a force braking a body).
};

/// Adds dt F_i / m_i to velocities[i] for every vertex i with a non-zero force that is not in
/// `pinned` (ascending ids); in vertex order, so the sums are the same at any thread count. A 2D
/// world's forces are in its plane already (World::addExternalForces projects them).
ExternalImpulse applyExternalImpulses(const std::vector<Vec3>& forces, const std::vector<Real>& masses,
                                      const std::vector<uint32_t>& pinned, Real dt, std::vector<Vec3>& velocities);

}  // namespace gradel
