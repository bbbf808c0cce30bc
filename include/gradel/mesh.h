// Triangle meshes: what mesh files are read into (voxelisation, embedded render meshes) and what
// display surfaces are exported as, one OBJ or PLY file per frame for Blender and the like.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "gradel/types.h"

namespace gradel {

struct TriangleMesh {
  std::vector<Vec3> vertices;                      ///< [m] (or the file's own units when read).
  std::vector<std::array<uint32_t, 3>> triangles;  ///< Counter-clockwise seen from outside.
  std::vector<Vec3> normals;                       ///< Optional, one per vertex (empty = none).
};

/// Writes Wavefront OBJ (v / vn / f lines). Throws InputError naming the path on failure.
void writeObj(const std::string& path, const TriangleMesh& mesh);
/// Writes binary little-endian PLY (vertex x y z [nx ny nz] float, face list uchar/int).
void writePly(const std::string& path, const TriangleMesh& mesh);

}  // namespace gradel
