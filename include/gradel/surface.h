// Display surfaces (paper sec. 3.3, figs. 7-8): triangle meshes whose corners are model vertices,
// built once on the rest lattice and then moved with the simulated vertices.
//
//   voxel   the staircase itself: every voxel face on the body's boundary (filled voxel, empty
//           face neighbour; outside the grid is empty), merged per element and plane into flat
//           polygons whose corners are model vertices, then triangulated. A polygon also takes
//           every model vertex on its edges (hanging vertices of finer or incomplete
//           neighbours), so two polygons always share the same vertices along a common edge:
//           no T-junction cracks.
//   smooth  the paper's display: the same mesh with faces laid over the concave steps. Every
//           edge where two triangles meet in a concave fold (the far corner of one triangle
//           lies outside the other's plane) is flipped to the other diagonal of the pair,
//           which lays a slanted face across the step (fig. 7); flips repeat until no concave
//           edge can be flipped without making a duplicate edge or a folded triangle.
//   2D      the flat body region, each element's region triangulated in the z = 0 plane;
//           `smooth` adds a triangle over every concave corner of the outline.
//
// Why model vertices only: the level-0 elements of a full 2x2x2 block own only its 8 corners,
// so the voxel corners in the middle of its faces are not simulated; a surface through them
// would need interpolation. Every corner of an exposed polygon is a model vertex (a corner of a
// filled level-0 cell, of this element or of the neighbour that covers the rest of the face).
//
// Orientation: triangles are counter-clockwise seen from outside (outward normals, positive
// enclosed volume); in 2D they face +z.
#pragma once

#include <array>
#include <vector>

#include "gradel/layout.h"
#include "gradel/mesh.h"

namespace gradel {

enum class SurfaceKind { Voxel, Smooth };
SurfaceKind parseSurfaceKind(const std::string& name);  ///< "voxel" | "smooth"; InputError otherwise.
const char* surfaceKindName(SurfaceKind k);

/// A display surface over the model's vertices (shared rest data: built once, read-only).
struct DisplaySurface {
  int dim = 3;
  SurfaceKind kind = SurfaceKind::Smooth;
  std::vector<uint32_t> modelVertex;               ///< Model vertex id of each surface vertex.
  std::vector<std::array<uint32_t, 3>> triangles;  ///< Surface vertex ids, CCW from outside.
  /// Smooth 3D surface: the normals drawn are restFieldNormals (the smoothed occupancy's,
  /// display_normals.h) carried from restMeshNormals (the mesh's own at rest) to its current
  /// ones. Empty: the mesh's own normals.
  std::vector<Vec3> restMeshNormals, restFieldNormals;
};

/// Builds the surface from the layout (and the volume it was built from). Pure function.
DisplaySurface buildDisplaySurface(const Layout& layout, const VoxelVolume& volume, SurfaceKind kind);

/// Moves the surface's model vertex ids by `offset`: a body's surface, built from its own layout,
/// onto the world's model of several bodies (offset = RestModel::bodies[i].vertexBegin, bodies.h).
void shiftVertexIds(DisplaySurface& surface, uint32_t offset);

/// The surface at the given model vertex positions [m]: vertices gathered from `positions`,
/// normals averaged from the neighbouring faces (area-weighted, unit length; +z in 2D); for the
/// smooth surface averaged once more over the neighbouring vertices, then (restFieldNormals set)
/// the field normals carried by those (display_normals.h).
TriangleMesh surfaceMesh(const DisplaySurface& surface, const std::vector<Vec3>& positions);

/// vertexNormals averaged once more over each vertex's neighbours (the smooth surface's own).
std::vector<Vec3> smoothVertexNormals(const std::vector<Vec3>& vertices,
                                      const std::vector<std::array<uint32_t, 3>>& triangles);

/// Unit vertex normals of `mesh` averaged from its faces, area-weighted (sec. 3.3). A vertex
/// with no face (or only degenerate ones) gets (0, 0, 1).
std::vector<Vec3> vertexNormals(const std::vector<Vec3>& vertices,
                                const std::vector<std::array<uint32_t, 3>>& triangles);

}  // namespace gradel
