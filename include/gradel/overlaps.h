// Bodies that start overlapping (issue 26): a body placed partly inside another body, a
// manipulator (a tool inside tissue) or a wall (across a wall, below the floor). Found once, at
// t = 0, and told on stderr (a warning: users place bodies by hand). The world then separates
// them at a capped speed instead of at once, so the separation stores no more energy than
// pushing at that speed does and ends within a bounded time (depth / kStartSeparationSpeed):
//   * a wall starts just outside the body and moves to its place at that speed;
//   * a manipulator starts shrunk about its centre until no vertex is inside, and grows back
//     to its size with its surface moving at that speed;
//   * two overlapping bodies are moved apart along the line of their centres, without any
//     change of velocity (the centre of mass and the momentum stay), by their overlap along it,
//     at that speed; contacts between bodies start once every such pair is apart.
// The energy the walls and manipulators store that way counts as supplied (contact_work.h).
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "gradel/contacts.h"
#include "gradel/model.h"
#include "gradel/types.h"

namespace gradel {

class World;

/// [m/s] the speed at which start overlaps are pushed apart.
constexpr Real kStartSeparationSpeed = 1.0;

struct StartOverlap {
  enum class With { Body, Manipulator, Wall };
  With with = With::Body;
  size_t body = 0;      ///< RestModel::bodies index.
  size_t other = 0;     ///< The other body, the manipulator, or the wall (kWalls index).
  Real depth = 0;       ///< [m] Body: overlap along the line of centres; else the deepest vertex inside.
  size_t vertices = 0;  ///< Vertices of `body` inside (Body: boundary vertices inside the other).
  Vec3 direction{1, 0, 0};  ///< Body: the unit direction `other` moves away from `body`.
  Real scale = 1;           ///< Manipulator: the share of its size with no vertex of any body inside.
  Real reach = 0;           ///< [m] Manipulator: its radius, or a cylinder's larger of radius and half length.
};

/// The overlaps of the world's bodies at its current state (meant for t = 0, the rest pose; the
/// world keeps what it found when it released them: World::startOverlaps()):
/// with the walls, the manipulators at their pose now, and, for 3D worlds with contacts
/// between bodies, each other (a vertex strictly inside another body's voxels).
std::vector<StartOverlap> findStartOverlaps(const World& world);

/// One line for stderr: what overlaps what, by how much, and how long the separation takes.
/// `names` the bodies' names (may be empty or shorter: then "body <i>").
std::string describeStartOverlap(const StartOverlap& o, const World& world, const std::vector<std::string>& names);

/// The largest scale s in [1e-6, 1] of a manipulator's size (radius, half length) about its
/// centre with no vertex of x[0, n) strictly inside (1 when none is inside at full size).
Real freeManipulatorScale(const Manipulator& m, const Vec3* x, size_t n);

/// Whether p lies strictly inside the voxels of `body` (its elements' blocks, rest pose moved by
/// `shift`), with a margin of 1e-6 voxel: touching faces do not overlap.
class BodyOccupancy {
 public:
  BodyOccupancy(const RestModel& model, const BodyRange& body);
  bool inside(const Vec3& p, const Vec3& shift) const;

 private:
  Vec3 origin_{0, 0, 0};
  Real h_ = 1;
  std::array<long, 3> lo_{0, 0, 0}, n_{0, 0, 0};
  std::vector<uint8_t> cells_;
  bool occupied(long i, long j, long k) const;
};

}  // namespace gradel
