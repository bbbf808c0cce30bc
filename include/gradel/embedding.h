// An embedded render mesh: a triangle mesh given in rest coordinates [m] (read from a file or
// made by the caller) carried along by the deforming elements, for display and export.
//
// Each mesh vertex is bound, at rest, to the element whose region holds it (the nearest element
// if it lies outside every region, e.g. a mesh slightly larger than its voxelisation). Its
// position is the element's least-squares affine fit evaluated at the vertex:
//   x(p) = c + A (p - c0),  c, c0 the element's current and rest vertex means,
//   A = (sum_i r_i R0_i^T) (sum_i R0_i R0_i^T)^-1,  r_i = x_i - c,  R0_i = X_i - c0.
// That is linear in the element's vertex positions, x(p) = sum_i w_i x_i with
// w_i = 1/n + R0_i . B^-1 (p - c0), so the weights are computed once and a frame costs one
// weighted sum per mesh vertex. It follows rigid motion (including the rotation of eq. 1) and
// any affine stretch exactly.
#pragma once

#include <vector>

#include "gradel/layout.h"
#include "gradel/mesh.h"
#include "gradel/model.h"

namespace gradel {

/// Shared rest data of an embedded mesh (immutable after embedMesh).
struct EmbeddedMesh {
  std::vector<std::array<uint32_t, 3>> triangles;  ///< As in the input mesh.
  std::vector<uint32_t>
      weightStart;  ///< Size mesh vertices + 1: weights of vertex v are [weightStart[v], weightStart[v+1]).
  std::vector<uint32_t> weightVertex;  ///< Model vertex id of each weight.
  std::vector<Real> weight;            ///< [-] sums to 1 per mesh vertex.
  std::vector<uint32_t> element;       ///< Element each mesh vertex is bound to.
  /// The input mesh's own normals (when it has them), drawn carried from restMeshNormals (the
  /// mesh's area-weighted normals at rest) to its current ones (display_normals.h); empty: the
  /// current area-weighted normals.
  std::vector<Vec3> restMeshNormals, restFieldNormals;
};

/// Binds `restMesh` (rest coordinates [m], the model's frame) to the model. Throws InputError
/// for an empty mesh, a triangle index out of range or a non-finite coordinate.
EmbeddedMesh embedMesh(const TriangleMesh& restMesh, const Layout& layout, const RestModel& model);

/// Moves the mesh's model vertex ids by `offset` (and its element ids by `elementOffset`): a body's
/// mesh, embedded in its own model, onto the world's model of several bodies (bodies.h).
void shiftVertexIds(EmbeddedMesh& embedded, uint32_t offset, uint32_t elementOffset = 0);

/// The embedded mesh at the given model vertex positions [m], with area-weighted vertex normals
/// (or, restFieldNormals set, those carried along by them).
TriangleMesh embeddedMesh(const EmbeddedMesh& embedded, const std::vector<Vec3>& positions);

}  // namespace gradel
