// What one call of the body-contact stage (BodyContacts::resolve, body_contacts.h) found.
#pragma once

#include <cstddef>

#include "gradel/types.h"

namespace gradel {

/// What one call found.
struct BodyContactStats {
  size_t candidates = 0;  ///< Vertex lookups in the narrow phase (all rounds).
  /// Of those, lookups of vertices that this stage's own corrections had moved (a contact's vertex
  /// or face corner, pushed out by an earlier round): each must be looked up again, whatever the
  /// bounds, since it ends a correction a skin away from the other body (docs/speed.md, "the floor").
  size_t movedLookups = 0;
  size_t contacts = 0;    ///< Vertex-face contacts resolved.
  Real maxDepth = 0;      ///< [m] deepest vertex found, before correction.
  int rounds = 0;         ///< Detection rounds run.
  int rebuilds = 0;       ///< Times the candidate lists kept across steps were rebuilt (see the header).
  int takeBacks = 0;      ///< Times the last resort took bodies back towards the step's start (0: not needed).
  size_t warm = 0;        ///< Contacts of the last stage that the warm start applied (found inside their plane).
  Real takenBackTo = 1;   ///< [-] the fraction of the step's motion the taken-back bodies kept.
  /// "Inside" findings deeper than the step's motion can reach that the winding number of the
  /// other body's surface said were outside (a folded surface misleads the pseudo-normal test):
  /// dropped, not pushed (dropUnreachable).
  size_t unreachable = 0;
  /// The narrow phase's work: nearest-point tests of a vertex against a face (all lookups, all
  /// rounds, the last resort's detections included).
  size_t faceTests = 0;
  /// Winding numbers of a closed surface evaluated (dropUnreachable, and allowedDepth's once per
  /// vertex and body at the step's start), each O(that surface's faces).
  size_t windingNumbers = 0;
  /// The stage's change of kinetic + elastic energy where it touched, as the metrics measure it
  /// (explicit steps; body_contact_energy.h), and what was taken out of the touched vertices'
  /// relative motion when that change was positive [J].
  Real energyExcess = 0, energyRemoved = 0;
  double seconds = 0;     ///< Wall time of the call (measurements; no result depends on it).
};

}  // namespace gradel
