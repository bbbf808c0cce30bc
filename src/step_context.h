// The step as a list of named stages (Box2D v3's b2StepContext and stage list, Jolt's
// SoftBodyUpdateContext): World::step runs
//   begin (constants once, ledger opened: StepContext)
//   -> integrator advance, dispatched once per step: explicit (step_explicit.cpp: element frames,
//      the fused vertex pass with its obstacle contacts), implicit (step_implicit.cpp) or large
//      step (step_large.cpp); each ends with the pins
//   -> body contacts (step_body_contacts.cpp: body_contacts.h's broad, narrow phase and response)
//   -> the obstacles' wall re-pass of the vertices the body contacts moved
//   -> finish (the ledger closed last: contact forces and work; step_obstacles.cpp, called by World::step).
// This header is private to those files: the context and the constants they share.
#pragma once

#include <vector>

#include "element_stage.h"
#include "gradel/contacts.h"
#include "gradel/integration.h"
#include "gradel/world.h"
#include "simd.h"
#include "thread_team.h"

namespace gradel {

// The explicit vertex stage's blocks: the broad phase's unit and the contact forces' partial sums.
constexpr size_t kVertexBlock = 16;
// Pair constraints (body contacts in the implicit solve) hold a vertex this far [voxel size of
// the face's body] outside the face: the post-step stage (skin 1e-6) then has nothing to do.
constexpr Real kPairGap = 1e-4;
// One vertex's contact impulse J = m dv on the body from `surface` at x, about `centre` (2D: x,
// centre and J in the plane z = 0, so the torque is about z).
inline void addImpulse(ContactForce& acc, const Vec3& J, const Vec3& x, const Vec3& centre) {
  acc.force += J, acc.torque += (x - centre).cross(J);
}

/// The step's context: what one step's stages pass on to each other. Set once per step by
/// World::beginStep (the constants) and filled by the stages (the start state, the contact
/// depths, the ledger); never read across steps except for output (maxContactDepth).
struct StepContext {
  // Constants of the step (beginStep).
  Real dt = 0;               ///< [s] the step.
  Real tNext = 0;            ///< [s] the time at its end.
  Vec3 gravity{0, 0, 0};     ///< [m/s^2] projected into a 2D body's plane (World()).
  bool obstacles = false;    ///< Manipulators or walls: the obstacle contacts run.
  bool bodyContacts = false; ///< Contacts between bodies run after the integrator (World::bodyContactsOn).
  bool symplectic = false;   ///< The stored velocity is half a step behind (contacts.h StepStart).
  // The step's data.
  std::vector<ElementFrame> frames;      ///< Per element: k M and (k e, k), written by the element stage.
  std::vector<Vec3> previousPositions;   ///< [m] start positions of a frame-size step (swept contacts).
  std::vector<Vec3> previousVelocities;  ///< [m/s] start velocities then (the bounce's crossing speed, contacts.h).
  std::vector<Real> contactDepth;        ///< [m] per vertex, implicit step only: depth before correction.
  Real maxContactDepth = 0;              ///< [m] deepest vertex found (and corrected) in the last step.
  // The force ledger. Contact impulses (World::stepContactForces): per surface (the manipulators, then each of the kWalls walls)
  // the impulse the contact response gave the body [N s] and its moment [N m s] (about the
  // manipulator's centre, the walls' about the origin). The explicit step sums them per aligned
  // block of kVertexBlock vertices, kept only for the blocks the broad phase let through
  // (TouchedBlocks, one list per team member), and adds the blocks in block order after the step:
  // the same sums at any thread count, and neither work nor memory for the blocks no contact can
  // reach (a dense array, blocks x surfaces, took 18 bytes a vertex with the walls alone).
  std::vector<ContactForce> impulse;
  /// One member's touched blocks of this step, in the order it handled them: block index, the
  /// contacts' work in it (contact_work.h) and its impulses (surfaces entries per block).
  struct TouchedBlocks {
    std::vector<uint32_t> block;
    std::vector<Real> work;
    std::vector<ContactForce> impulse;
  };
  std::vector<TouchedBlocks> touched;  ///< Per team member (at least one).
  std::vector<int> contactSurface;  ///< Per vertex, implicit step: the surface that moved it last (-1: none).
  Real work = 0;  ///< The energy the contacts gave the bodies this step (contact_work.h).
};

/// The vertices an implicit step holds in its second solve (projective.h): where, the direction
/// their contact pushed them, the surface that did (a manipulator's index, a wall's K + kWalls
/// index) and its friction.
struct World::HeldContacts {
  std::vector<uint32_t> vertices;
  std::vector<Vec3> at, normal;
  std::vector<int> surface;
  std::vector<Real> friction;
  std::vector<char> letGo;  ///< Per hold: starts let go (a vertex touching a surface at the step's start).
  std::vector<Vec3> slip;   ///< Per hold: its vertex's sliding on its surface over the last step (a first guess).
};

}  // namespace gradel
