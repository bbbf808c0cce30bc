// The viewer's display-mesh budget: what a frame may cost in surface triangles, and the coarser
// display mesh a body larger than that is drawn with.
//
// Software OpenGL (llvmpipe, what this machine and most VMs have) rasterises on the CPU at about
// 0.6 us per triangle on top of ~15 ms for the window and panel (docs/viewer.md): the smooth
// surface of a sphere of size 128 (142,704 triangles) made every frame cost over 100 ms. Above the
// budget the viewer draws the body's isosurface sampled every `step` voxels (isosurface.h),
// embedded in the full model (embedding.h: each of its vertices follows its element's affine fit,
// exact for rigid and affine motion), so the physics and its vertices are untouched and a frame's
// surface work is bounded whatever the size. The panel says when it is coarse and can switch the
// full surface back on.
#pragma once

#include <cstddef>

#include "gradel/mesh.h"
#include "gradel/volume.h"

namespace gradel::render {

/// [triangles] the viewer's default display budget: about 40 ms of llvmpipe CPU per frame, and the
/// size-64 sphere's smooth surface (36,336) still drawn whole.
constexpr size_t kDisplayTriangleBudget = 40000;

/// The first isosurface step worth trying for a surface of `triangles` triangles under `budget`:
/// the smallest s >= 1 with triangles / s^2 <= budget (a surface's triangles go as its area).
/// 1 when it fits or when `budget` is 0 (no budget).
int displayStepEstimate(size_t triangles, size_t budget);

/// A display mesh of at most `budget` triangles.
struct CoarseSurface {
  TriangleMesh mesh;
  int step = 1;  ///< The isosurface's sampling step [voxels].
};

/// The isosurface of `volume` (origin as in isosurface()) at the smallest step from `firstStep`
/// up whose mesh has at most `budget` triangles (or the step at which a sample block covers the
/// whole volume, whatever its count; never an empty mesh when a finer step had triangles).
/// InputError as isosurface(), or for a budget of 0.
CoarseSurface coarseIsosurface(const VoxelVolume& volume, const Vec3& origin, size_t budget, int firstStep);

}  // namespace gradel::render
