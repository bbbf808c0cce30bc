// Mesh voxelisation: a triangle mesh becomes a binary VoxelVolume.
//
// The mesh is scaled so its longest bounding-box edge spans `resolution` voxels and centred in
// a grid just large enough to hold it. A voxel is filled when its centre is inside, decided by
// three votes, one per axis: along the axis, rays through voxel centres collect their signed
// crossings with the triangles (+1 entering through a face whose normal points against the ray,
// -1 leaving), and the running sum is the winding number of the mesh around each centre on that
// ray. A ray whose sum does not return to zero at the far end crossed a hole or a flipped face;
// it abstains. A voxel is filled when more voting axes see a non-zero winding number than a
// zero one.
//
//   * closed, consistently oriented meshes (either orientation): exact, every axis agrees;
//   * overlapping closed parts (a union of shells): winding >= 1 inside any part, so the union;
//   * holes and stray flipped faces: only the rays that pass them abstain, so the other axes
//     decide; a mesh open along every axis (a single sheet) gives an empty volume, an error.
//
// Rays that graze an edge or a vertex are counted once by a tie rule shared by the two
// triangles on either side (a "top-left" rule on an edge direction fixed by its endpoints'
// order), so a closed mesh never gains or loses a crossing there.
#pragma once

#include <string>

#include "gradel/mesh.h"
#include "gradel/volume.h"

namespace gradel::io {

struct VoxelizeSettings {
  int resolution = 64;    ///< [voxels] along the mesh's longest bounding-box edge, 1 to 1024.
  Real voxelSize = 0.01;  ///< [m] edge of one voxel in the resulting volume.
  /// Crossings allowed per axis: max(this, 64 per ray) (ReadLimits::minRayCrossingCap).
  uint64_t minCrossingCap = uint64_t(1) << 20;
};

/// Voxelises `mesh` (3D). `name` (the file) starts every InputError: no triangles, indices out
/// of range, non-finite or flat extent, a resolution out of range, or nothing inside.
/// When `latticeMesh` is given it receives `mesh` placed in the volume's lattice (units of one
/// voxel edge, lattice point (0,0,0) = voxel (0,0,0)'s lower corner): the same vertices and
/// triangles, scaled and shifted exactly as they were voxelised, no normals. A body built from the
/// volume at origin o then has the mesh at rest at o + voxelSize * p (its embedded render mesh).
VoxelVolume voxelize(const TriangleMesh& mesh, const VoxelizeSettings& settings, const std::string& name,
                     TriangleMesh* latticeMesh = nullptr);

}  // namespace gradel::io
