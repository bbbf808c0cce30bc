// Triangle mesh files read into gradel::TriangleMesh (mesh.h) for voxelisation:
//   * Wavefront OBJ: "v x y z" and "f a b c ..." lines (a, a/t, a//n, a/t/n; negative indices
//     count back from the last vertex); polygons are fanned into triangles; everything else
//     (vt, vn, groups, materials, lines) is skipped.
//   * STL, binary (80-byte header, uint32 count, 50 bytes a triangle) or ASCII ("solid" ...
//     "facet normal" / "outer loop" / "vertex x y z" x 3 / "endloop"); binary is recognised by
//     its exact size, because many binary files also start with the word "solid".
//   * PLY, ascii / binary_little_endian / binary_big_endian: element "vertex" (properties
//     x, y, z) and element "face" (list property vertex_indices or vertex_index); other elements
//     and properties are skipped.
// Vertices are in the file's own units; coordinates must be finite. Indices must name existing
// vertices. Everything else is an InputError naming the file, the line (text) or the element.
#pragma once

#include <string>

#include "gradel/io/byte_stream.h"
#include "gradel/io/read_limits.h"
#include "gradel/mesh.h"

namespace gradel::io {

TriangleMesh readObj(ByteStream& in, const ReadLimits& limits = {});
TriangleMesh readStl(ByteStream& in, const ReadLimits& limits = {});
TriangleMesh readPly(ByteStream& in, const ReadLimits& limits = {});

}  // namespace gradel::io
