// A body cut into pieces (issue 30): the mechanically connected components of a body's layout,
// and the body split into one body per piece.
//
// Connectivity follows the layout: two elements are connected when they share a vertex (own or
// hanging: every vertex on an element's closed region belongs to it, layout.h), since a shared
// vertex is what couples elements in the shape-matching step; a voxel belongs to the piece of
// the element holding it. On every layout this is the same as voxels touching at a face, an
// edge or a corner (26-connectivity in 3D, 8 in 2D): voxels touching at a corner are surface
// voxels of finest elements whose corners are vertices lying on both regions, and the filled
// cells of one incomplete element touch at least at a corner.
//
// Each piece keeps the body's lattice (the same grid dimensions and origin, so the layout's
// alignment and every surviving vertex's lattice point are the same) and is laid out again by
// the body's own rule; the state is carried over as carveBody does (carve.h): a vertex at a
// lattice point that was a vertex keeps its position and velocity bit for bit, a new one (where
// the piece's own layout differs from the body's) takes the trilinear interpolation of its old
// mass cell, and the new vertices share one velocity so that the piece's momentum is that of the
// body's vertices it holds. Pieces are vertex-disjoint, so the pieces' masses and momenta add up
// to the body's.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "gradel/carve.h"
#include "gradel/layout.h"
#include "gradel/model.h"
#include "gradel/volume.h"

namespace gradel {

/// The pieces of a body, numbered largest first (filled voxels), ties by the lowest voxel index.
struct BodyPieces {
  std::vector<int32_t> voxelPiece;   ///< Per voxel (storage order): its piece, -1 when empty.
  std::vector<int32_t> vertexPiece;  ///< Per vertex of the layout: its piece.
  std::vector<size_t> voxels;        ///< Per piece: its filled voxels.
  size_t count() const { return voxels.size(); }
};

/// The connected components of the layout (above). std::invalid_argument when the volume is not the layout's.
BodyPieces findPieces(const Layout& layout, const VoxelVolume& volume);

/// One piece as a body of its own: volume (the body's grid holding the piece's voxels only),
/// layout, rest model and state.
struct BodyPiece {
  VoxelVolume volume;
  Layout layout;
  std::shared_ptr<const RestModel> model;
  std::vector<Vec3> positions, velocities;
  std::vector<Quat> rotations;
  std::vector<uint32_t> fromVertex;  ///< Per vertex: the body's vertex id, or Layout::kNoVertex.
  size_t newVertices = 0;
  Vec3 momentumCorrection{0, 0, 0};  ///< [m/s] added to the new vertices' interpolated velocities.
};

/// The body split into its pieces (findPieces' order). A body of one piece gives an empty vector
/// (nothing to split). std::invalid_argument for null inputs (carve.h CarveInput).
std::vector<BodyPiece> splitBody(const CarveInput& body);

}  // namespace gradel
