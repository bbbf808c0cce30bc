#include "gradel/embedding.h"

#include "gradel/display_normals.h"
#include "gradel/surface.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
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
            if (x < n[0] && y < n[1] && z < n[2])
              owner[size_t(x) + size_t(n[0]) * (size_t(y) + size_t(n[1]) * size_t(z))] = int32_t(e);
    }
  }
  return owner;
}

// Squared distance [voxels^2] from lattice point q to voxel (i, j, k)'s cube (in 2D: its square).
Real boxDistance2(const Vec3& q, int i, int j, int k, int dim) {
  Real d2 = 0;
  const int c[3] = {i, j, k};
  for (int a = 0; a < dim; ++a) {
    const Real lo = c[a], hi = c[a] + 1.0;
    const Real d = q[a] < lo ? lo - q[a] : q[a] > hi ? q[a] - hi : 0.0;
    d2 += d * d;
  }
  return d2;
}

// Owner of the filled voxel nearest to lattice point q (in voxel cell `cell`, possibly outside
// the grid): the element whose region is nearest. Shells of growing Chebyshev radius around the
// cell first (a voxel in shell r is at least r - 1 voxels away, so the search stops once the best
// is nearer than that), then, for a point far from the body, every filled voxel.
int32_t nearestOwner(const Layout& layout, const std::vector<int32_t>& owner, const Vec3& q, const Int3& cell) {
  const auto& n = layout.dims;
  const int dim = layout.dim;
  auto at = [&](int i, int j, int k) {
    return owner[size_t(i) + size_t(n[0]) * (size_t(j) + size_t(n[1]) * size_t(k))];
  };
  Real best = std::numeric_limits<Real>::infinity();
  int32_t e = -1;
  constexpr int kMaxShell = 8;
  for (int r = 1; r <= kMaxShell; ++r) {
    const int k0 = dim == 3 ? std::max(0, cell.z() - r) : 0, k1 = dim == 3 ? std::min(n[2] - 1, cell.z() + r) : 0;
    const int j0 = std::max(0, cell.y() - r), j1 = std::min(n[1] - 1, cell.y() + r);
    const int i0 = std::max(0, cell.x() - r), i1 = std::min(n[0] - 1, cell.x() + r);
    for (int k = k0; k <= k1; ++k)
      for (int j = j0; j <= j1; ++j)
        for (int i = i0; i <= i1; ++i) {
          const int cheb =
              std::max({std::abs(i - cell.x()), std::abs(j - cell.y()), dim == 3 ? std::abs(k - cell.z()) : 0});
          if (cheb != r) continue;  // inner shells are done
          const int32_t o = at(i, j, k);
          if (o < 0) continue;
          if (const Real d = boxDistance2(q, i, j, k, dim); d < best) best = d, e = o;
        }
    if (e >= 0 && best <= Real(r) * Real(r)) return e;  // shell r + 1 is at least r away
  }
  for (int k = 0; k < n[2]; ++k)
    for (int j = 0; j < n[1]; ++j)
      for (int i = 0; i < n[0]; ++i)
        if (const int32_t o = at(i, j, k); o >= 0)
          if (const Real d = boxDistance2(q, i, j, k, dim); d < best) best = d, e = o;
  return e;
}

Vec3 restMean(const RestModel& m, size_t e) {
  Vec3 c = Vec3::Zero();
  for (uint32_t p = m.elemStart[e]; p < m.elemStart[e + 1]; ++p) c += m.restPositions[m.elemVerts[p]];
  return c / Real(m.elemStart[e + 1] - m.elemStart[e]);
}

}  // namespace

EmbeddedMesh embedMesh(const TriangleMesh& restMesh, const Layout& layout, const RestModel& model) {
  if (restMesh.vertices.empty() || restMesh.triangles.empty())
    throw InputError("embedded mesh: no vertices or no triangles");
  for (const auto& t : restMesh.triangles)
    for (uint32_t v : t)
      if (v >= restMesh.vertices.size())
        throw InputError("embedded mesh: triangle index " + std::to_string(v) + " out of range");
  for (const Vec3& p : restMesh.vertices)
    if (!p.allFinite()) throw InputError("embedded mesh: non-finite vertex coordinate");

  const Real h = model.voxelSize;
  const Vec3& origin = model.origin;  // world position of lattice point (0,0,0) (model.h)
  const std::vector<int32_t> owner = voxelOwners(layout);
  std::vector<Vec3> means(model.numElements());
  for (size_t e = 0; e < means.size(); ++e) means[e] = restMean(model, e);

  EmbeddedMesh out;
  out.triangles = restMesh.triangles;
  if (restMesh.normals.size() == restMesh.vertices.size()) {
    out.restMeshNormals = vertexNormals(restMesh.vertices, restMesh.triangles);
    out.restFieldNormals = restMesh.normals;
    for (Vec3& n : out.restFieldNormals) n = n.norm() > 0 && n.allFinite() ? Vec3(n.normalized()) : Vec3::Zero();
  }
  out.weightStart.push_back(0);
  for (const Vec3& p : restMesh.vertices) {
    const Vec3 q = (p - origin) / h;
    // Clamped first: a vertex a million voxels away still finds the nearest element, without overflow.
    auto cellOf = [](Real c) { return int(std::floor(std::clamp(c, -1e6, 1e6))); };
    const int x = cellOf(q.x()), y = cellOf(q.y()), z = layout.dim == 3 ? cellOf(q.z()) : 0;
    int32_t e = -1;
    if (x >= 0 && y >= 0 && z >= 0 && x < layout.dims[0] && y < layout.dims[1] && z < layout.dims[2])
      e = owner[size_t(x) + size_t(layout.dims[0]) * (size_t(y) + size_t(layout.dims[1]) * size_t(z))];
    if (e < 0) e = nearestOwner(layout, owner, q, {x, y, z});
    if (e < 0) throw InputError("embedded mesh: the body has no elements");
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
  if (!embedded.restFieldNormals.empty())
    m.normals = carryNormals(m.normals, embedded.restMeshNormals, embedded.restFieldNormals);
  return m;
}

}  // namespace gradel

namespace gradel {

void shiftVertexIds(EmbeddedMesh& embedded, uint32_t offset, uint32_t elementOffset) {
  for (uint32_t& v : embedded.weightVertex) v += offset;
  for (uint32_t& e : embedded.element) e += elementOffset;
}

}  // namespace gradel
