// Carving in a built scene (issue 30): a body of a BuiltScene loses voxels (carve.h carveBody),
// its volume, layout and rest model are replaced, and its World is made again over the new model
// (World::replaceModel) with every other body's state as it was and the carved body's carried
// over (a new vertex that would lie inside a manipulator put on its surface); the contact surfaces are rebuilt from the bodies' layouts when the world has body contacts.
// A carved body whose material falls apart becomes one body per piece (pieces.h): the largest
// keeps its index and name, the others are appended after every body, named "<name>-2",
// "<name>-3", ... (the smallest number no body has); in 3D the world then has contact between
// the bodies (the pieces collide like any two bodies); a pin of the body holds each piece it
// selects vertices of; the removed-material ledger stays with the body's index (new pieces
// start at zero: nothing was removed from them).
// A body voxelised from a mesh loses its embedded render mesh (drawn by its voxel surface after).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "gradel/carve.h"
#include "gradel/scene.h"

namespace gradel {

/// What one event did to one body.
struct CarveEvent {
  size_t body = 0;
  size_t removedVoxels = 0;
  Real removedVolume = 0;         ///< [m^3]
  Real removedMass = 0;           ///< [kg]
  Vec3 removedMomentum{0, 0, 0};  ///< [kg m/s]
  Real removedKineticEnergy = 0;  ///< [J]
  size_t newVertices = 0;
  size_t vertices = 0, elements = 0;  ///< The body's (its pieces' together), after.
  /// The scene bodies holding the body's material after the event: {body}, or when it fell apart
  /// (pieces.h) `body` (the largest piece, its name kept) then the new bodies appended for the others.
  std::vector<size_t> pieces;
};

/// The body's part of a world (scene.h BuiltScene::range): its volume, layout, own model and state.
CarveInput carveInput(const BuiltScene& scene, size_t body);

/// Removes the voxels of `remove` (carve.h) from body `body` and replaces it in the world. An
/// event that would remove nothing or every voxel changes nothing (removedVoxels 0).
/// std::out_of_range for a body index past the bodies.
CarveEvent carveSceneBody(BuiltScene& scene, size_t body, const std::vector<uint8_t>& remove);

/// Every body's voxels whose deformed centres lie within `radius` of the segment from `from` to
/// `to` (a sphere swept over a step; from == to: a sphere), the radius grown by `reachVoxels` of
/// each body's voxel size: one event per body that loses any, the world made again once. Only
/// voxels whose region label is in `labels` (ascending; empty: every label), here and below.
std::vector<CarveEvent> carveSceneSweep(BuiltScene& scene, const Vec3& from, const Vec3& to, Real radius,
                                        Real reachVoxels = 0, const std::vector<uint16_t>& labels = {});

/// The same for a cylinder (carve.h voxelsInCylinder: `axis`, `radius`, `halfLength` [m]) moved
/// from `from` to `to`, its radius and half length grown by `reachVoxels` of each body's voxel size.
std::vector<CarveEvent> carveSceneCylinderSweep(BuiltScene& scene, const Vec3& from, const Vec3& to, const Vec3& axis,
                                                Real radius, Real halfLength, Real reachVoxels = 0,
                                                const std::vector<uint16_t>& labels = {});

/// Every 3D body's kerf along the blade's sweep (carve.h voxelsAlongBlade; no reach: a blade
/// never pushes, it cuts exactly where it passes): one event per body that loses any.
std::vector<CarveEvent> carveSceneBlade(BuiltScene& scene, const BladeSweep& blade,
                                        const std::vector<uint16_t>& labels = {});

/// The manipulators with `carve` set (and every blade: carveSceneBlade) (spheres and cylinders): each removes the voxels within one
/// voxel of what it swept (a cylinder: grown by one voxel in radius and half length; a carving
/// tool still pushes the body like any manipulator, so the surface it meets stays about half a
/// voxel outside it) since `previous` (its centre at
/// the last call, one entry per manipulator; updated to the centres now; empty or of another
/// size: the centres now, so the first call carves where the tools are). A tool with
/// `carveLabels` removes only voxels of those regions.
std::vector<CarveEvent> carveWithManipulators(BuiltScene& scene, std::vector<Vec3>& previous);

}  // namespace gradel
