// The lattice kernels shared by carving and splitting into pieces (carve_cells.h).
#include "carve_cells.h"

#include <stdexcept>

namespace gradel::carve_cells {

void checkInput(const CarveInput& b) {
  if (!b.volume || !b.layout || !b.model || !b.positions || !b.velocities)
    throw std::invalid_argument("carve: null volume, layout, model or state");
  if (b.model->numVertices() != b.layout->numVertices() || b.model->numElements() != b.layout->numElements())
    throw std::invalid_argument("carve: the model is not the layout's (a body's own model, scene.h BuiltBody)");
}

MassCell massCell(const Layout& layout, const Int3& lo, int edge) {
  MassCell m;
  m.lo = lo, m.edge = edge, m.corners = cornerCount(layout.dim);
  for (int k = 0; k < m.corners; ++k) {
    m.corner[k] = layout.vertexAt(lo + cornerOffset(k, layout.dim) * edge);
    if (m.corner[k] == Layout::kNoVertex) throw std::logic_error("carve: a mass cell's corner is not a vertex");
  }
  return m;
}

std::array<Real, 8> trilinear(const Vec3& t, int dim) {
  std::array<Real, 8> w{};
  for (int k = 0; k < cornerCount(dim); ++k) {
    Real p = 1;
    for (int a = 0; a < dim; ++a) p *= (k >> a & 1) ? t[a] : 1 - t[a];
    w[k] = p;
  }
  return w;
}

std::vector<int32_t> voxelOwners(const Layout& layout, const VoxelVolume& volume) {
  std::vector<int32_t> owner(volume.size(), -1);
  const int D = layout.dim;
  forEachMassCell(layout, [&](size_t e, const Int3& lo, int edge) {
    for (int k = 0; k < (D == 3 ? edge : 1); ++k)
      for (int j = 0; j < edge; ++j)
        for (int i = 0; i < edge; ++i) owner[volume.index(lo.x() + i, lo.y() + j, lo.z() + k)] = int32_t(e);
  });
  return owner;
}

MassCell cellOfVoxel(const Layout& layout, size_t e, const Int3& q) {
  const int cs = layout.cellSize[e];
  if (layout.isFull(e)) return massCell(layout, layout.origin[e], 2 * cs);
  Int3 lo = layout.origin[e];
  for (int a = 0; a < layout.dim; ++a) lo[a] += (q[a] - lo[a]) / cs * cs;
  return massCell(layout, lo, cs);
}

Transferred transferState(const Layout& oldLayout, const std::vector<int32_t>& owner, const VoxelVolume& oldVolume,
                          const Vec3* oldPositions, const Vec3* oldVelocities, const Quat* oldRotations,
                          const VoxelVolume& volume, const Layout& layout, const RestModel& model,
                          const Vec3& targetMomentum) {
  const int D = layout.dim;
  const size_t V = layout.numVertices(), E = layout.numElements();
  Transferred out;
  out.positions.resize(V), out.velocities.resize(V), out.fromVertex.resize(V);
  for (size_t v = 0; v < V; ++v) {
    const Int3& p = layout.vertices[v];
    const uint32_t was = oldLayout.vertexAt(p);
    out.fromVertex[v] = was;
    if (was != Layout::kNoVertex) {
      out.positions[v] = oldPositions[was], out.velocities[v] = oldVelocities[was];
      continue;
    }
    // A new vertex: a corner of some filled voxel of the new volume (held by an old element).
    int32_t e = -1;
    Int3 q(0, 0, 0);
    for (int c = 0; c < cornerCount(D) && e < 0; ++c) {
      q = p - cornerOffset(c, D);
      if (volume.at(q.x(), q.y(), q.z())) e = owner[oldVolume.index(q.x(), q.y(), q.z())];
    }
    if (e < 0) throw std::logic_error("carve: a new vertex touches no voxel");
    const MassCell c = cellOfVoxel(oldLayout, size_t(e), q);
    const std::array<Real, 8> w = trilinear(localPoint(c, p.cast<Real>()), D);
    out.positions[v] = interpolate(c, w, oldPositions), out.velocities[v] = interpolate(c, w, oldVelocities);
    ++out.newVertices;
  }
  // Momentum: the target, the difference over the new vertices.
  Vec3 after = Vec3::Zero();
  Real newMass = 0;
  for (size_t v = 0; v < V; ++v) {
    after += model.mass[v] * out.velocities[v];
    if (out.fromVertex[v] == Layout::kNoVertex) newMass += model.mass[v];
  }
  if (newMass > 0) {
    out.momentumCorrection = (targetMomentum - after) / newMass;
    for (size_t v = 0; v < V; ++v)
      if (out.fromVertex[v] == Layout::kNoVertex) out.velocities[v] += out.momentumCorrection;
  }
  // Warm starts: the rotation of the old element at each new element's first filled cell.
  out.rotations.assign(E, Quat::Identity());
  if (oldRotations)
    for (size_t e = 0; e < E; ++e) {
      int c = 0;
      while (!(layout.cellMask[e] >> c & 1)) ++c;
      const Int3 q = layout.origin[e] + cornerOffset(c, D) * layout.cellSize[e];
      out.rotations[e] = oldRotations[owner[oldVolume.index(q.x(), q.y(), q.z())]];
    }
  return out;
}

}  // namespace gradel::carve_cells
