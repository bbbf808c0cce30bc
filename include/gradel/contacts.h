// Contacts (paper sec. 3.5): an axis-aligned box domain with walls, and kinematic rigid
// manipulators (sphere or capped cylinder in 3D, circle in 2D) that follow a scripted path or a
// pose set from outside. A vertex that enters a manipulator is put back on its surface and its
// velocity, relative to the manipulator (its moving frame), is reflected: the normal part times
// -restitution (1 = the paper's elastic bounce), the tangential part reduced by Coulomb friction.
// The test is swept in the manipulator's frame, so a fast manipulator cannot pass through a vertex.
//
// A contact never adds energy (relative to the obstacle's frame; issue 15: a cylinder held through
// a damped body raised its energy x26 in 0.6 s, a sphere pressing it into a wall x13). Two rules:
// 1. The bounce is restitution times the normal speed at which the vertex *approached*, not the
//    speed it ends the step with: with u0, u1 its normal velocity (relative to the surface) at the
//    start and end of the step, s0 >= 0 its distance outside at the start and a = (u1 - u0) / dt,
//    the crossing speed is min(|u0|, |u1|, sqrt(u0^2 - 2 a s0)). The speed gained *inside* the
//    obstacle from the force that presses the vertex in is never returned (reflecting it every
//    step pumped the body up). A vertex that started the step receding (u0 >= 0) and was turned
//    back within it, or that started inside, made no flight the step can resolve: resting
//    contact, no bounce (like Box2D's restitution threshold, without a scale-dependent constant).
// 2. The position projection lifts the vertex by `lift` against the normal acceleration a < 0
//    that pressed it in, storing |a| lift per unit mass of elastic (or gravity) energy; that
//    energy is taken out of the vertex's kinetic energy relative to the surface, first from the
//    bounce, then from the sliding. Without it a frictionless restitution-0 contact still gained
//    energy (x5 for the cylinder). The sliding loss is 1/2 (a dt)^2 per step at most: a numerical
//    friction of order dt that vanishes as dt -> 0.
// With symplectic Euler (StepStart::leapfrog) both act on the normal velocity at the time of the
// positions, wn = vn + a dt / 2 (its stored velocity is the leapfrog v_{n+1/2}; metrics()
// measures the kinetic energy with the same correction; forward Euler's and the implicit step's
// velocities are synchronous, wn = vn): the bounce sends the vertex off at e times min(crossing speed, |wn|) and
// stores that minus a dt / 2; a vertex with wn >= 0 keeps its velocity. Reflecting vn instead
// gained m |vn| a dt (1 + e) / 2 per bounce of a vertex pulled away from the surface (a > 0) by
// a fast element mode (issue 15: 1.2 J -> 290 J near omega dt = 0.8). A resting vertex is left
// with wn = 0 (stored velocity -a dt / 2).
// A real strike keeps the paper's elastic bounce (a vertex hit at speed leaves at that speed, less
// the O(dt) stored energy). Without the vertex's start-of-step velocity (`StepStart`, unit tests
// of single impacts) both rules are off and the end velocity is reflected.

#pragma once

#include <optional>
#include <string>
#include <vector>

#include "gradel/types.h"

namespace gradel {

/// Blade (3D): a flat rectangle that cuts (carve_scene.h) and never pushes: no vertex is ever
/// inside it, so it has no contact and exerts no force (docs/carving.md, "The blade").
enum class ManipulatorShape { Sphere, Cylinder, Circle, Blade };
ManipulatorShape parseManipulatorShape(const std::string& name);  ///< "sphere" | "cylinder" | "circle" | "blade"
const char* manipulatorShapeName(ManipulatorShape s);

struct Keyframe {
  Real time = 0;                 ///< [s]
  Vec3 position{0, 0, 0};        ///< [m] centre of the manipulator.
  std::optional<Vec3> velocity;  ///< [m/s] optional; with both ends given a segment is cubic Hermite, else linear.
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
  Real radius = 0.02;      ///< [m]
  Real halfLength = 0.05;  ///< [m] cylinder only: half the length of its axis (flat caps).
  Vec3 axis{0, 0, 1};      ///< cylinder only: axis direction (normalised when built).
  Real restitution = 1.0;  ///< [-] 1 = elastic bounce (the paper), 0 = no bounce.
  Real friction = 0.0;     ///< [-] Coulomb coefficient; 0 = frictionless (the paper).
  Path path;               ///< Scripted motion; empty = pose set from outside (setPose).
  bool carve = false;      ///< Sphere or cylinder: removes the voxels whose centres it sweeps (carve_scene.h); a blade always cuts.
  /// The region labels a carving tool removes (ascending, distinct, 1..65535); empty: every
  /// label. Voxels of other regions in its sweep stay (a sphere or cylinder still pushes them):
  /// a selective tool, e.g. an aspirator that takes soft tissue and spares a stiffer structure.
  std::vector<uint16_t> carveLabels;
  /// Blade only: the rectangle centre +- halfLength along `axis` +- halfWidth along `widthAxis`
  /// (both normalised when built, perpendicular); its normal is axis x widthAxis.
  Vec3 widthAxis{1, 0, 0};
  Real halfWidth = 0.05;  ///< [m]
};

/// The walls of the domain box, by index: 2 a + 1 for the wall at max[a], 2 a at min[a] (a the
/// axis): xmin, xmax, ymin, ymax, zmin, zmax (a 2D domain has the first four).
constexpr int kWalls = 6;
/// "xmin", "xmax", "ymin", "ymax", "zmin", "zmax".
const char* wallName(int wall);

struct DomainSettings {
  bool enabled = false;    ///< No walls when false.
  Vec3 min{-1, -1, -1};    ///< [m] lower corner of the box.
  Vec3 max{1, 1, 1};       ///< [m] upper corner.
  Real restitution = 0.5;  ///< [-] of the walls.
  Real friction = 0.0;     ///< [-] Coulomb coefficient of the walls.
};

/// A manipulator's runtime pose (kinematic: it moves, it is never pushed).
struct Manipulator {
  ManipulatorSettings settings;
  Vec3 position{0, 0, 0};          ///< [m] centre now.
  Vec3 velocity{0, 0, 0};          ///< [m/s]
  Vec3 previousPosition{0, 0, 0};  ///< [m] centre at the start of the current step (for the swept test).

  /// Signed distance [m] from the surface (negative inside) and outward normal at p.
  Real signedDistance(const Vec3& p, Vec3* normal) const;
};

/// Result of resolving one vertex.
struct ContactResult {
  Real depth = 0;  ///< [m] how far the vertex was inside before it was pushed out (0 = no contact).
  int wall = -1;   ///< resolveDomain: the last wall (kWalls index) that pushed the vertex, -1 none.
};

/// The vertex's velocity at the start of the step and the step [s]: what the bounce needs to find
/// the speed at which the vertex crossed the surface (see above).
struct StepStart {
  Vec3 velocity{0, 0, 0};  ///< [m/s] before this step's forces acted.
  Real dt = 0;             ///< [s] > 0.
  bool leapfrog = false;   ///< Velocities half a step behind the positions (symplectic Euler): see above.
};

/// Resolves one vertex against one manipulator, in place. xPrev is the vertex position at the
/// start of the step (for the swept test); `start` its velocity then (for the bounce; without it
/// the bounce reflects the end velocity v, which adds energy under sustained contact: only for
/// a single isolated impact, as in unit tests). With bounce == false the contact is inelastic
/// (restitution 0): used when a vertex pinched between two surfaces is resolved again, so that
/// repeated reflections cannot pump energy into it. Pure function of its arguments. In 2D the
/// vertex and the manipulator's pose are in the plane z = 0 already (World's API: src/plane.h), and
/// so is the result.
ContactResult resolveManipulator(const Manipulator& m, const Vec3& xPrev, Vec3& x, Vec3& v, bool bounce = true,
                                 const StepStart* start = nullptr);

/// Resolves one vertex against the domain walls, in place (bounce and start as above). xPrev as
/// above: friction also acts on the position (see contacts.cpp, frictionSlipCorrection).
/// `wallDv`, when given (kWalls entries), gets each wall's velocity change of the vertex added
/// (the forces per wall); their sum is the vertex's total change to rounding.
ContactResult resolveDomain(const DomainSettings& d, const Vec3& xPrev, Vec3& x, Vec3& v, int dim, bool bounce = true,
                            const StepStart* start = nullptr, Vec3* wallDv = nullptr);

}  // namespace gradel
