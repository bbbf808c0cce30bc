// What a World is created from besides its rest model (model.h) and the bodies' contact surfaces
// (body_contacts.h): the settings a user fills in, each with its default (Box2D's b2WorldDef,
// Jolt's settings / shared rest data / runtime state split). World(model, settings, contacts)
// builds the complete world from them in one call; buildScene fills them from a Scene.
#pragma once

#include <vector>

#include "gradel/body_contacts.h"
#include "gradel/contacts.h"
#include "gradel/integrator.h"
#include "gradel/pins.h"

namespace gradel {

struct WorldSettings {
  SimulationSettings simulation;                  ///< Integrator, dt (or auto), damping, gravity, threads.
  DomainSettings domain;                          ///< The walls (off by default).
  std::vector<ManipulatorSettings> manipulators;  ///< Kinematic tools, in index order (contacts.h).
  /// Boundary conditions (pins.h), their mask files already read (loadPinMasks: the World reads
  /// no file). Empty: nothing pinned.
  std::vector<PinSettings> pins;
  /// Contact between the bodies (and of a body with itself): used when contact surfaces are given.
  BodyContactSettings bodyContact;
  /// [m/s] initial velocity of every vertex of body i (RestModel::bodies), z ignored in 2D.
  /// Empty: all at rest; otherwise one entry per body.
  std::vector<Vec3> bodyVelocities;
  /// Bodies placed overlapping each other, a manipulator or a wall are separated at
  /// kStartSeparationSpeed (overlaps.h, World::releaseStartOverlaps); false: the contacts' instant push.
  bool releaseStartOverlaps = true;
};

}  // namespace gradel
