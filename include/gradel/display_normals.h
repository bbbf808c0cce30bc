// Display normals that look like the object (issue 28): the gradient of the body's occupancy
// smoothed by a Gaussian, taken at rest and carried along by the deformation. Display only: the
// physics never reads them.
//
// A voxelised sphere is a staircase. Normals averaged from the mesh's own faces show its steps:
// facets at size 12, and at 64 or 128 concentric terrace rings near the poles, where the steps
// are about sqrt(2 R) voxels apart (R the radius in voxels). The occupancy blurred with a
// Gaussian of about that width has a gradient close to the true surface's normal there, and on a
// flat face it is the face's normal; edges and corners come out rounded over about sigma voxels.
//
// Each frame a vertex's normal is its rest field normal g turned by the smallest rotation that
// takes the mesh's own rest normal a to its current one b (about a x b): g exactly at rest and
// after a translation, and it turns with the surface as the body moves and deforms. That
// rotation leaves out the twist about the normal, so after a turn of the whole body g is off by
// up to the angle between g and a times the twist (test_surface.cpp: a 10^3 sphere turned by
// 0.9 rad, 4.2 degrees off on average and 19.7 at most; its own normals are 8.4 off the sphere).
#pragma once

#include <vector>

#include "gradel/types.h"
#include "gradel/volume.h"

namespace gradel {

/// [voxels] The Gaussian's standard deviation for `volume`: 0.5 sqrt(n) for a body n voxels
/// across (its largest side), at least 1 (sizes 12 / 32 / 64 / 128: 1.7 / 2.8 / 4 / 5.7).
Real displayNormalSigma(const VoxelVolume& volume);

/// Unit outward normals at `points` given in lattice coordinates [voxels] (voxel (i,j,k) spans
/// [i, i+1] x [j, j+1] x [k, k+1]): minus the gradient of the occupancy blurred with a Gaussian of
/// `sigma` voxels (three box passes per axis), trilinearly interpolated from the voxel centres.
/// A point where the gradient vanishes gets (0, 0, 0). 3D volumes only (InputError otherwise).
std::vector<Vec3> fieldNormals(const VoxelVolume& volume, const std::vector<Vec3>& points, Real sigma);

/// The normals to draw: restField[v] turned by the smallest rotation from rest[v] to now[v] (all
/// unit length). Where restField[v] is zero or the turn is more than about 150 degrees: now[v].
std::vector<Vec3> carryNormals(const std::vector<Vec3>& now, const std::vector<Vec3>& rest,
                               const std::vector<Vec3>& restField);

}  // namespace gradel
