// Boundary conditions: pinned regions (a clamped beam, a held organ). A pin selects every model
// vertex whose rest position lies in an axis-aligned box and prescribes its position: the rest
// position plus the pin's path offset at time t (no path: fixed at rest). Explicit integrators
// overwrite pinned vertices' position and velocity after each step; the implicit integrator
// eliminates them from its linear system (projective.h).
#pragma once

#include <vector>

#include "gradel/contacts.h"

namespace gradel {

struct PinSettings {
  Vec3 min{0, 0, 0};  ///< [m] lower corner of the box, world coordinates at rest.
  Vec3 max{0, 0, 0};  ///< [m] upper corner (closed box: vertices on its faces are pinned).
  Path path;          ///< Keyframe `position` = offset [m] of the pinned vertices from rest; empty = fixed.
};

/// The pinned vertices of a model: ids (ascending) and, per id, the index of the pin that holds it
/// (the first pin whose box contains it).
struct PinSet {
  std::vector<uint32_t> vertices;  ///< Pinned vertex ids, ascending.
  std::vector<uint32_t> pinOf;     ///< Per entry of `vertices`: index into the settings list.
  bool empty() const { return vertices.empty(); }
};

/// Selects the pinned vertices from rest positions. Throws InputError when a pin holds no vertex
/// or its box is inverted (message "pins[i]: ...").
PinSet selectPins(const std::vector<PinSettings>& pins, const std::vector<Vec3>& restPositions);

}  // namespace gradel
