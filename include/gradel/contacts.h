// Contacts (paper sec. 3.5): an axis-aligned box domain with walls, and kinematic rigid
// manipulators (sphere or capped cylinder in 3D, circle in 2D) that follow a scripted path or a
// pose set from outside. A vertex that enters a manipulator is put back on its surface and its
// velocity, relative to the manipulator (its moving frame), is reflected: the normal part times
// -restitution (1 = the paper's elastic bounce), the tangential part reduced by Coulomb friction.
// The test is swept in the manipulator's frame, so a fast manipulator cannot pass through a vertex.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "gradel/types.h"

namespace gradel {

enum class ManipulatorShape { Sphere, Cylinder, Circle };
ManipulatorShape parseManipulatorShape(const std::string& name);  ///< "sphere" | "cylinder" | "circle"
const char* manipulatorShapeName(ManipulatorShape s);

struct Keyframe {
  Real time = 0;                  ///< [s]
  Vec3 position{0, 0, 0};         ///< [m] centre of the manipulator.
  std::optional<Vec3> velocity;   ///< [m/s] optional; with both ends given a segment is cubic Hermite, else linear.
};

/// A path of keyframes sorted by time. Before the first key the manipulator rests at it; after the
/// last it keeps the last key's velocity if one was given, else rests.
struct Path {
  std::vector<Keyframe> keys;
  Vec3 position(Real t) const;
  Vec3 velocity(Real t) const;
};

struct ManipulatorSettings {
  ManipulatorShape shape = ManipulatorShape::Sphere;
  Real radius = 0.02;            ///< [m]
  Real halfLength = 0.05;        ///< [m] cylinder only: half the length of its axis (flat caps).
  Vec3 axis{0, 0, 1};            ///< cylinder only: axis direction (normalised when built).
  Real restitution = 1.0;        ///< [-] 1 = elastic bounce (the paper), 0 = no bounce.
  Real friction = 0.0;           ///< [-] Coulomb coefficient; 0 = frictionless (the paper).
  Path path;                     ///< Scripted motion; empty = pose set from outside (setPose).
};

struct DomainSettings {
  bool enabled = false;           ///< No walls when false.
  Vec3 min{-1, -1, -1};           ///< [m] lower corner of the box.
  Vec3 max{1, 1, 1};              ///< [m] upper corner.
  Real restitution = 0.5;         ///< [-] of the walls.
  Real friction = 0.0;            ///< [-] Coulomb coefficient of the walls.
};

/// A manipulator's runtime pose (kinematic: it moves, it is never pushed).
struct Manipulator {
  ManipulatorSettings settings;
  Vec3 position{0, 0, 0};  ///< [m] centre now.
  Vec3 velocity{0, 0, 0};  ///< [m/s]
  Vec3 previousPosition{0, 0, 0};  ///< [m] centre at the start of the current step (for the swept test).

  /// Signed distance [m] from the surface (negative inside) and outward normal at p.
  Real signedDistance(const Vec3& p, Vec3* normal) const;
};

/// Result of resolving one vertex.
struct ContactResult {
  Real depth = 0;  ///< [m] how far the vertex was inside before it was pushed out (0 = no contact).
};

/// Resolves one vertex against one manipulator, in place. xPrev is the vertex position at the
/// start of the step (for the swept test). With bounce == false the contact is inelastic
/// (restitution 0): used when a vertex pinched between two surfaces is resolved again, so that
/// repeated reflections cannot pump energy into it. Pure function of its arguments.
ContactResult resolveManipulator(const Manipulator& m, const Vec3& xPrev, Vec3& x, Vec3& v, int dim,
                                 bool bounce = true);

/// Resolves one vertex against the domain walls, in place (bounce as above). xPrev as above:
/// friction also acts on the position (see contacts.cpp, frictionSlipCorrection).
ContactResult resolveDomain(const DomainSettings& d, const Vec3& xPrev, Vec3& x, Vec3& v, int dim,
                            bool bounce = true);

}  // namespace gradel
