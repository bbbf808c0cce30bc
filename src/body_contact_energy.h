// The body-contact stage never adds energy (issue 26 item 1): its change of the kinetic + elastic
// energy of the region it touched, measured as the metrics measure it, and when positive taken
// out of the touched vertices' motion relative to one another (momentum kept).
//
// Why: the stage pushes vertices out along the contact normal (positions) and then applies
// impulses that never add kinetic energy (body_contact_response.cpp). The push stores elastic
// energy that the impulses pay only by an estimate (the relative acceleration times the depth),
// and with restitution 0 nothing pays it. Measured (a 7^3 ball of E = 4e4 Pa into a 6^3 one of
// 1e4 Pa at rest, 1 m/s, restitution 0, dt_fraction 0.25): each contact step the stage added
// 1e-5 to 3e-5 J (0.1-0.35 % of the pair's energy) and 1.6e-4 / 2.4e-4 J in the two steps where a
// vertex and a face corner of the other body crossed each other's surface; the pair parted with
// 1.021x its energy (peak 1.039x, the random-pairs property's third case). A stiff box at 8 m/s
// into a soft ball reached 97x. docs/speed.md "The stage's energy cap".
//
// The measure is the metrics' (World::metrics): elastic energy of the touched vertices' elements
// (the only ones whose shape the stage changed), plus the kinetic energy of those elements'
// vertices at w = v + a dt / 2 (symplectic Euler's velocity is half a step behind its positions,
// and the stage's pushes change a through the forces of every element of those vertices). It is
// compared before (the touched vertices where and how fast they were when the stage began) and
// after, for each group of bodies the contacts link on its own. An excess e > 0 is taken out
// with dv_i = -s (w_i - mean w) over the group's touched vertices that can move: their kinetic energy changes by -K_rel (2 s - s^2), K_rel their kinetic energy
// about the mean, so s = 1 - sqrt(1 - e / K_rel), at most 1 (all of K_rel, when e exceeds it).
// The sum of m dv is zero: linear momentum is kept to rounding.
//
// Serial, in a fixed order (elements ascending, vertices in the stage's order): the same result at
// any thread count. Explicit steps only (the frame-size steps measure energy differently).
#pragma once

#include <cstdint>
#include <vector>

#include "gradel/body_contacts.h"
#include "gradel/model.h"
#include "gradel/types.h"

namespace gradel {

/// What one cap did.
struct ContactEnergyCap {
  Real excess = 0;   ///< [J] the stage's change of the measured energy (> 0: it added energy).
  Real removed = 0;  ///< [J] taken out of the touched vertices' relative motion.
  Real scale = 0;    ///< [-] s above (0: nothing done).
};

/// The touched region of one stage and where it began (BodyContacts::touched, touchedStart,
/// touchedStartVelocity), with the state it acts on.
struct ContactEnergyInput {
  const std::vector<uint32_t>* touched = nullptr;
  const std::vector<Vec3>* startPositions = nullptr;
  const std::vector<Vec3>* startVelocities = nullptr;
  const std::vector<BodyContacts::Contact>* contacts = nullptr;  ///< The stage's contacts (they group the touched).
  const Quat* rotations = nullptr;  ///< Per element: the warm start of its fit.
  const Real* movable = nullptr;    ///< Per vertex: 0 = not moved by the cap (pinned).
  Vec3 gravity = Vec3::Zero();
  Real dt = 0;
};

/// The cap's scratch: which elements hold a vertex (built once per model), and marks.
class ContactEnergyLimiter {
 public:
  /// Measures the stage's change of energy and takes an excess out of x's velocities v (the
  /// touched vertices only). Positions are read, never changed.
  ContactEnergyCap apply(const RestModel& m, const ContactEnergyInput& in, Vec3* x, Vec3* v);

 private:
  void prepare(const RestModel& m);
  ContactEnergyCap capGroup(const RestModel& m, const ContactEnergyInput& in, Vec3* x, Vec3* v);
  void elementsOf(const std::vector<uint32_t>& verts, std::vector<uint32_t>& out);
  Real measure(const RestModel& m, const ContactEnergyInput& in, const Vec3* x, const Vec3* v, std::vector<Vec3>& w);

  const RestModel* model_ = nullptr;
  std::vector<uint32_t> vertexStart_, vertexElements_;  ///< Per vertex its elements (CSR, ascending).
  std::vector<uint32_t> elementMark_, vertexMark_, slot_;
  uint32_t mark_ = 0;
  std::vector<uint32_t> inner_, ring_, outer_;  ///< Elements of the touched, their vertices, those's elements.
  std::vector<uint8_t> isInner_;                ///< Per element of outer_: also in inner_.
  std::vector<Vec3> force_, f_, offsets_, start_, wBefore_, wAfter_, vNow_;
  std::vector<uint32_t> parent_, order_, group_, groupT_;  ///< Union-find over the bodies; per touched vertex its group; one group's vertices.
  std::vector<Vec3> groupX0_, groupV0_;
};

}  // namespace gradel
