// A smooth surface of a voxel volume, for embedding (embedding.h) when no render mesh is given:
// the 0.5 level set of the occupancy smoothed by a 3x3x3 box average, sampled at voxel centres
// and extracted by marching tetrahedra (the marching-cubes family: each lattice cube split
// into six tetrahedra around its main diagonal, so no 256-case table is needed and
// neighbouring cubes always agree on shared faces: the mesh is closed).
//
// On a flat face of the volume the level set lies exactly on the voxel faces; edges and
// corners come out rounded by about one voxel.
#pragma once

#include "gradel/mesh.h"
#include "gradel/volume.h"

namespace gradel {

/// The isosurface of a 3D volume in metres (lattice point (0,0,0) at `origin`), triangles
/// counter-clockwise seen from outside, vertices shared (closed, consistently oriented), with
/// normals from the occupancy smoothed by a Gaussian (display_normals.h; no terraces). Throws InputError for a 2D or
/// empty volume. `step` > 1 samples every step-th voxel: the level set of the filled share of the 3 step voxels a side
/// around each sample (blocks of step^3 voxels taken as one), about step^2 times fewer triangles with corners rounded
/// by about `step` voxels (the viewer's display budget, render/display_budget.h); step 1 is the full-resolution surface
/// above. InputError for step < 1.
TriangleMesh isosurface(const VoxelVolume& volume, const Vec3& origin, int step = 1);

}  // namespace gradel
