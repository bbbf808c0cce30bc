#include "gradel/embedding.h"

#include <cmath>
#include <limits>

#include "gradel/surface.h"

namespace gradel {

namespace {

// Owner element of every voxel (-1 = empty), from the elements' filled cells.
std::vector<int32_t> voxelOwners(const Layout& layout) {
  const auto& n = layout.dims;
  std::vector<int32_t> owner(size_t(n[0]) * size_t(n[1]) * size_t(n[2]), -1);
  for (size_t e = 0; e < layout.numElements(); ++e) {
    const int32_t c = layout.cellSize[e];
    for (int k = 0; k < 8; ++k) {
      if (!(layout.cellMask[e] >> k & 1)) continue;
      const Int3 lo = layout.origin[e] + c * Int3(k & 1, k >> 1 & 1, k >> 2 & 1);
      const int32_t cz = layout.dim == 3 ? c : 1;
      for (int32_t z = lo.z(); z < lo.z() + cz; ++z)
        for (int32_t y = lo.y(); y < lo.y() + c; ++y)
          for (int32_t x = lo.x(); x < lo.x() + c; ++x)
            if (x < n[0] && y < n[1] && z < n[2]) owner[size_t(x) + size_t(n[0]) * (size_t(y) + size_t(n[1]) * size_t(z))] = int32_t(e);
    }
  }
  return owner;
}

Vec3 restMean(const RestModel& m, size_t e) {
  Vec3 c = Vec3::Zero();
  for (uint32_t p = m.elemStart[e]; p < m.elemStart[e + 1]; ++p) c += m.restPositions[m.elemVerts[p]];
  return c / Real(m.elemStart[e + 1] - m.elemStart[e]);
}

}  // namespace

EmbeddedMesh embedMesh(const TriangleMesh& restMesh, const Layout& layout, const RestModel& model) {
  if (restMesh.vertices.empty() || restMesh.triangles.empty()) throw InputError("embedded mesh: no vertices or no triangles");
  for (const auto& t : restMesh.triangles)
    for (uint32_t v : t)
      if (v >= restMesh.vertices.size()) throw InputError("embedded mesh: triangle index " + std::to_string(v) + " out of range");
  for (const Vec3& p : restMesh.vertices)
    if (!p.allFinite()) throw InputError("embedded mesh: non-finite vertex coordinate");

  // World position of lattice point (0,0,0): restPositions = origin + lattice * h (model.h).
  const Real h = model.voxelSize;
  const Vec3 origin = model.restPositions[0] - layout.vertices[0].cast<Real>() * h;
  const std::vector<int32_t> owner = voxelOwners(layout);
  std::vector<Vec3> means(model.numElements());
  for (size_t e = 0; e < means.size(); ++e) means[e] = restMean(model, e);

  EmbeddedMesh out;
  out.triangles = restMesh.triangles;
  out.weightStart.push_back(0);
  for (const Vec3& p : restMesh.vertices) {
    const Vec3 q = (p - origin) / h;
    const int x = int(std::floor(q.x())), y = int(std::floor(q.y())), z = layout.dim == 3 ? int(std::floor(q.z())) : 0;
    int32_t e = -1;
    if (x >= 0 && y >= 0 && z >= 0 && x < layout.dims[0] && y < layout.dims[1] && z < layout.dims[2])
      e = owner[size_t(x) + size_t(layout.dims[0]) * (size_t(y) + size_t(layout.dims[1]) * size_t(z))];
    if (e < 0) {  // just outside: the owner of the nearest filled voxel among the 26 neighbours
      Real best = std::numeric_limits<Real>::infinity();
      for (int dz = (layout.dim == 3 ? -1 : 0); dz <= (layout.dim == 3 ? 1 : 0); ++dz)
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            const int i = x + dx, j = y + dy, k = z + dz;
            if (i < 0 || j < 0 || k < 0 || i >= layout.dims[0] || j >= layout.dims[1] || k >= layout.dims[2]) continue;
            const int32_t o = owner[size_t(i) + size_t(layout.dims[0]) * (size_t(j) + size_t(layout.dims[1]) * size_t(k))];
            const Vec3 centre = origin + h * Vec3(i + 0.5, j + 0.5, layout.dim == 3 ? k + 0.5 : p.z() / h);
            if (o >= 0 && (centre - p).squaredNorm() < best) best = (centre - p).squaredNorm(), e = o;
          }
    }
    if (e < 0) {  // farther out: the element with the nearest rest mean
      Real best = std::numeric_limits<Real>::infinity();
      for (size_t k = 0; k < means.size(); ++k)
        if (const Real d = (means[k] - p).squaredNorm(); d < best) best = d, e = int32_t(k);
    }
    const uint32_t b = model.elemStart[size_t(e)], n = model.elemStart[size_t(e) + 1] - b;
    Mat3 B = Mat3::Zero();
    for (uint32_t i = b; i < b + n; ++i) {
      const Vec3 r0 = model.restPositions[model.elemVerts[i]] - means[size_t(e)];
      B += r0 * r0.transpose();
    }
    // In 2D the z row and column are zero: invert the xy block only.
    Mat3 Binv = Mat3::Zero();
    if (layout.dim == 3)
      Binv = B.inverse();
    else
      Binv.topLeftCorner<2, 2>() = B.topLeftCorner<2, 2>().inverse();
    const Vec3 g = Binv * (p - means[size_t(e)]);
    for (uint32_t i = b; i < b + n; ++i) {
      const Vec3 r0 = model.restPositions[model.elemVerts[i]] - means[size_t(e)];
      out.weightVertex.push_back(model.elemVerts[i]);
      out.weight.push_back(1.0 / n + r0.dot(g));
    }
    out.weightStart.push_back(uint32_t(out.weight.size()));
    out.element.push_back(uint32_t(e));
  }
  return out;
}

TriangleMesh embeddedMesh(const EmbeddedMesh& embedded, const std::vector<Vec3>& positions) {
  TriangleMesh m;
  const size_t nv = embedded.weightStart.size() - 1;
  m.vertices.assign(nv, Vec3::Zero());
  for (size_t v = 0; v < nv; ++v)
    for (uint32_t k = embedded.weightStart[v]; k < embedded.weightStart[v + 1]; ++k)
      m.vertices[v] += embedded.weight[k] * positions[embedded.weightVertex[k]];
  m.triangles = embedded.triangles;
  m.normals = vertexNormals(m.vertices, m.triangles);
  return m;
}

}  // namespace gradel
