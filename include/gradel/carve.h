// Carving (issue 30): removing voxels from a living elastic body. The event is a pure function of
// the body's voxel volume, layout, rest model and state and of the voxels to remove: the volume
// minus those voxels is laid out again by the gradational rule (today a full re-layout of the
// body: buildLayout + buildRestModel), and the state is carried over.
//
// State transfer
//   * Every vertex of the new layout that was a vertex of the old one (the same lattice point)
//     keeps its position and velocity bit for bit.
//   * A new vertex takes the trilinear interpolation of the deformed positions and velocities of
//     the corners of the old mass cell that held its rest position (material.h: a full element's
//     block, or a filled cell of an incomplete one; its corners are always model vertices).
//     Trilinear, not the element's best-fit affine map: the mean of a trilinear field over the
//     corners of any box inside the cell is its value at the box's centre, so a cell split into
//     finer cells keeps its lumped momentum exactly.
//   * Mass: the removed voxels' mass leaves (consistent scaling: the new total is the old one
//     minus rho h^3 per removed voxel of its region, up to rounding).
//   * Momentum: the removed material carries the momentum of its voxels (voxel mass times the
//     trilinear velocity at the voxel's centre, `removedMomentum`). Where the transfer alone does
//     not give old - removed exactly (a surviving vertex that was hanging on a coarse cell's face
//     keeps its own velocity, not the cell's interpolation), the difference is spread over the
//     new vertices as one velocity (`momentumCorrection`), never over surviving vertices.
//   * Best-fit rotations (the warm start of eq. 1): an element of the new layout takes the one of
//     the old element that held the voxel at its first filled cell's lower corner.
//
// Pieces: carveBody returns one body whatever its shape; a scene splits a carved body that fell
// apart into one body per piece (pieces.h, carve_scene.h). Removing every voxel is refused
// (`emptied`: the body is returned unchanged).
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "gradel/layout.h"
#include "gradel/model.h"
#include "gradel/volume.h"

namespace gradel {

/// One body before a carving event: its volume, layout and own rest model (vertex ids from 0,
/// scene.h BuiltBody) and its state (one entry per vertex of `model`, rotations one per element;
/// rotations may be null: the new ones are then the identity).
struct CarveInput {
  const VoxelVolume* volume = nullptr;
  const Layout* layout = nullptr;
  const RestModel* model = nullptr;
  const Vec3* positions = nullptr;
  const Vec3* velocities = nullptr;
  const Quat* rotations = nullptr;
};

/// The body after the event and what left it.
struct CarvedBody {
  VoxelVolume volume;
  Layout layout;
  std::shared_ptr<const RestModel> model;
  std::vector<Vec3> positions, velocities;  ///< Per new vertex.
  std::vector<Quat> rotations;              ///< Per new element (warm starts).
  std::vector<uint32_t> fromVertex;  ///< Per new vertex: its old id, or Layout::kNoVertex for a new vertex.
  size_t removedVoxels = 0;          ///< Filled voxels of the mask (empty or masked-twice voxels not counted).
  size_t newVertices = 0;            ///< Vertices that were not vertices before.
  Real removedVolume = 0;            ///< [m^3] removedVoxels x h^3 (2D: a voxel is a slab one voxel thick).
  Real removedMass = 0;              ///< [kg] sum of the removed voxels' masses.
  Vec3 removedMomentum{0, 0, 0};     ///< [kg m/s] the removed voxels' momentum (see above).
  Real removedKineticEnergy = 0;     ///< [J] 1/2 m |v|^2 per removed voxel, v at its centre.
  Vec3 momentumCorrection{0, 0, 0};  ///< [m/s] added to every new vertex's interpolated velocity.
  bool emptied = false;              ///< The mask held every voxel: nothing done.
};

/// The carving event. `remove` has one byte per voxel of the volume (storage order, volume.h),
/// non-zero: remove. An event that removes no filled voxel returns a copy of the body and state.
/// std::invalid_argument for null inputs or a mask of the wrong size.
CarvedBody carveBody(const CarveInput& body, const std::vector<uint8_t>& remove);

/// The voxels (mask as `remove` above) whose centres lie inside the sphere (centre [m], radius
/// [m]) in the deformed configuration: each voxel centre mapped by the trilinear interpolation of
/// its mass cell's deformed corners. `count` (optional): how many.
std::vector<uint8_t> voxelsInSphere(const CarveInput& body, const Vec3& centre, Real radius, size_t* count = nullptr);

/// The voxels swept by a sphere moving from `from` to `to` (a capsule) this step, as voxelsInSphere.
std::vector<uint8_t> voxelsInCapsule(const CarveInput& body, const Vec3& from, const Vec3& to, Real radius,
                                     size_t* count = nullptr);

/// The voxels swept by a cylinder (a rod: `radius` [m], half its length `halfLength` [m] along
/// `axis`, flat caps) whose centre moves from `from` to `to` without turning, as voxelsInSphere.
/// The swept solid is a prism: across the axis the disc swept along the move's part across it (a
/// stadium), along the axis [min(0, d.a) - halfLength, max(0, d.a) + halfLength] from `from` (d
/// the move, a the unit axis). std::invalid_argument for a zero or non-finite axis.
std::vector<uint8_t> voxelsInCylinder(const CarveInput& body, const Vec3& from, const Vec3& to, const Vec3& axis,
                                      Real radius, Real halfLength, size_t* count = nullptr);

/// A blade (contacts.h ManipulatorShape::Blade): the rectangle centre +- halfLength along the
/// unit `axis` +- halfWidth along the unit `widthAxis` (perpendicular), normal n = axis x
/// widthAxis, moved without turning from `from` to `to`.
struct BladeSweep {
  Vec3 from{0, 0, 0}, to{0, 0, 0};
  Vec3 axis{1, 0, 0}, widthAxis{0, 1, 0};
  Real halfLength = 0, halfWidth = 0;
};

/// The blade's kerf: the voxels whose deformed centre x, at some moment t in [0, 1] of the
/// sweep, lies over the rectangle (its projection along n inside it: the rectangle's edges are
/// exact, not grown) and within the kerf's half width w of its plane: -w < n.(x - c(t)) <= w.
/// w = 1/2 |F^T n|_1, F the voxel's mass cell's deformed lattice frame (its mean edge vectors
/// per voxel; h I at rest, so w = h/2 (|n_x| + |n_y| + |n_z|)). Why: a blade whose normal is
/// a lattice axis takes exactly one voxel layer (the half-open slab of width h holds one layer of
/// centres); a tilted one takes the thinnest digital layer that separates voxels touching at an
/// edge or a corner (the arithmetic "standard" plane), since those share a vertex and would hold
/// the pieces together (pieces.h) -- a slab of width h at 45 degrees leaves them touching.
/// std::invalid_argument for a 2D body or axes that are zero, not finite or not perpendicular.
std::vector<uint8_t> voxelsAlongBlade(const CarveInput& body, const BladeSweep& blade, size_t* count = nullptr);

}  // namespace gradel
