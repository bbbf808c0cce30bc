// A body's contact surface for body contacts (body_contacts.h): its closed voxel display surface
// (surface.h, SurfaceKind::Voxel) with ids shifted to the world's vertex numbering, the faces
// around each boundary vertex (for the pseudo-normals) and, for self-contact, the vertices near
// each one. Rest data: built once, read-only.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "gradel/model.h"
#include "gradel/surface.h"
#include "gradel/types.h"

namespace gradel {

/// One body's contact surface (rest data: built once, read-only). Vertex ids are the world's.
struct ContactBody {
  uint32_t vertexBegin = 0, vertexEnd = 0;  ///< The body's vertices [begin, end).
  Real thickness = 0;                       ///< [m] about the body's voxel size: grid cell and search band.
  /// Its boundary vertices (world ids, ascending): the surface's corners and the model's other
  /// onSurface vertices (inside a merged polygon of a coarse element's face).
  std::vector<uint32_t> vertices;
  std::vector<std::array<uint32_t, 3>> triangles;  ///< World vertex ids, CCW from outside (closed surface).
  // Per boundary vertex (index into `vertices`): its triangles (CSR), for the pseudo-normals (a
  // vertex inside a polygon: the triangles that hold it at rest).
  std::vector<uint32_t> vertexTriStart, vertexTris;
  // Self-contact only: per surface vertex, the world ids of the vertices near it (of its elements
  // and its ring of surface faces), ascending (CSR); a face with a corner among them is adjacent.
  std::vector<uint32_t> nearStart, near;
  /// Per vertex of the body (world id - vertexBegin): its index in `vertices`, or kNone.
  std::vector<uint32_t> indexOf;

  /// Index of a world vertex id in `vertices`, or kNone.
  uint32_t surfaceIndex(uint32_t vertex) const {
    return vertex >= vertexBegin && vertex < vertexEnd ? indexOf[vertex - vertexBegin] : kNone;
  }
  static constexpr uint32_t kNone = 0xffffffffu;
};

/// The elements of a body, compressed rows: element e's vertices are verts[start[e]] .. verts[start[e+1] - 1],
/// for e in [begin, end); a vertex's world id is verts[p] + shift (shift = 0 when `verts` holds world ids
/// already, as in a combined model, or the body's vertex offset for a model of its own).
struct ElementRows {
  const uint32_t* start = nullptr;
  const uint32_t* verts = nullptr;
  size_t begin = 0, end = 0;
  uint32_t shift = 0;
};

/// Builds a body's contact surface from its voxel display surface (model vertex ids of the body,
/// shifted by vertexBegin), its rest positions and onSurface flags (RestModel; indexed from the
/// body's first vertex) and, for self-contact, its elements. `thickness` is the body's voxel size.
/// Throws std::invalid_argument if the surface is 2D or a corner lies outside [vertexBegin, vertexEnd).
ContactBody buildContactBody(const DisplaySurface& surface, uint32_t vertexBegin, uint32_t vertexEnd, Real thickness,
                             const Vec3* rest, const uint8_t* onSurface, const ElementRows& elements);

/// The contact surfaces of a world's bodies: body i (RestModel::bodies[i] of `world`, bodies.h)
/// from its own layout and volume (the voxel display surface), thickness its voxel size.
/// std::invalid_argument if the counts differ from the model's bodies.
std::vector<ContactBody> buildContactBodies(const RestModel& world, const std::vector<const Layout*>& layouts,
                                            const std::vector<const VoxelVolume*>& volumes);

}  // namespace gradel
