// Carving: the event (carveBody) and the voxel sets of a tool (voxelsInSphere, voxelsInCapsule,
// voxelsInCylinder).
// carve.h says what is kept and why.
#include "gradel/carve.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <vector>

#include "gradel/material.h"

namespace gradel {

namespace {

// A mass cell of the old layout (material.h): element e's block when full, else one filled cell;
// it gives its mass to its 2^dim corners, which are model vertices.
struct MassCell {
  Int3 lo{0, 0, 0};
  int edge = 1;  // [voxels]
  std::array<uint32_t, 8> corner{};
  int corners = 8;
};

int cornerCount(int dim) { return dim == 3 ? 8 : 4; }
Int3 cornerOffset(int k, int dim) { return Int3(k & 1, (k >> 1) & 1, dim == 3 ? (k >> 2) & 1 : 0); }

// Calls f(e, lo, edge) for every mass cell of the layout, in element order.
template <class F>
void forEachMassCell(const Layout& layout, F&& f) {
  const int cells = cornerCount(layout.dim);
  for (size_t e = 0; e < layout.numElements(); ++e) {
    const int cs = layout.cellSize[e];
    if (layout.isFull(e)) {
      f(e, layout.origin[e], 2 * cs);
      continue;
    }
    for (int c = 0; c < cells; ++c)
      if (layout.cellMask[e] >> c & 1) f(e, Int3(layout.origin[e] + cornerOffset(c, layout.dim) * cs), cs);
  }
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

// Trilinear weights of the local point t in [0, 1]^dim.
std::array<Real, 8> trilinear(const Vec3& t, int dim) {
  std::array<Real, 8> w{};
  for (int k = 0; k < cornerCount(dim); ++k) {
    Real p = 1;
    for (int a = 0; a < dim; ++a) p *= (k >> a & 1) ? t[a] : 1 - t[a];
    w[k] = p;
  }
  return w;
}

template <class T>
T interpolate(const MassCell& c, const std::array<Real, 8>& w, const T* values) {
  T s = T::Zero();
  for (int k = 0; k < c.corners; ++k) s += w[k] * values[c.corner[k]];
  return s;
}

Vec3 localPoint(const MassCell& c, const Vec3& latticePoint) {
  return (latticePoint - c.lo.cast<Real>()) / Real(c.edge);
}

// Per voxel (storage order), the old element holding it (-1: empty).
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

// The mass cell of element e holding voxel q.
MassCell cellOfVoxel(const Layout& layout, size_t e, const Int3& q) {
  const int cs = layout.cellSize[e];
  if (layout.isFull(e)) return massCell(layout, layout.origin[e], 2 * cs);
  Int3 lo = layout.origin[e];
  for (int a = 0; a < layout.dim; ++a) lo[a] += (q[a] - lo[a]) / cs * cs;
  return massCell(layout, lo, cs);
}

void checkInput(const CarveInput& b) {
  if (!b.volume || !b.layout || !b.model || !b.positions || !b.velocities)
    throw std::invalid_argument("carve: null volume, layout, model or state");
  if (b.model->numVertices() != b.layout->numVertices() || b.model->numElements() != b.layout->numElements())
    throw std::invalid_argument("carve: the model is not the layout's (a body's own model, scene.h BuiltBody)");
}

// Voxel mass [kg] of each label's material (consistent scaling: rho h^3; paper: the same voxel mass).
Real voxelMass(const RestModel& m, uint16_t label, Real h, int dim) {
  size_t i = 0;
  while (i + 1 < m.materialLabel.size() && m.materialLabel[i] != label) ++i;
  return cellCornerMass(m.materials[i], h, 1, dim) * cornerCount(dim);
}

// Marks the voxels whose deformed centre satisfies inside(x), cells culled by their corners' box
// with `near(lo, hi)` (the trilinear map stays inside its corners' convex hull).
template <class Near, class Inside>
std::vector<uint8_t> voxelsWhere(const CarveInput& b, Near&& near, Inside&& inside, size_t* count) {
  checkInput(b);
  const Layout& layout = *b.layout;
  const VoxelVolume& volume = *b.volume;
  const int D = layout.dim;
  std::vector<uint8_t> mask(volume.size(), 0);
  size_t n = 0;
  forEachMassCell(layout, [&](size_t, const Int3& lo, int edge) {
    const MassCell c = massCell(layout, lo, edge);
    Vec3 bmin = b.positions[c.corner[0]], bmax = bmin;
    for (int k = 1; k < c.corners; ++k)
      bmin = bmin.cwiseMin(b.positions[c.corner[k]]), bmax = bmax.cwiseMax(b.positions[c.corner[k]]);
    if (!near(bmin, bmax)) return;
    for (int k = 0; k < (D == 3 ? edge : 1); ++k)
      for (int j = 0; j < edge; ++j)
        for (int i = 0; i < edge; ++i) {
          const Vec3 centre(lo.x() + i + 0.5, lo.y() + j + 0.5, D == 3 ? lo.z() + k + 0.5 : 0.0);
          const Vec3 x = interpolate(c, trilinear(localPoint(c, centre), D), b.positions);
          if (!inside(x)) continue;
          uint8_t& m = mask[volume.index(lo.x() + i, lo.y() + j, lo.z() + k)];
          if (!m) m = 1, ++n;
        }
  });
  if (count) *count = n;
  return mask;
}

Real boxDistance(const Vec3& p, const Vec3& lo, const Vec3& hi) {
  return (p - p.cwiseMax(lo).cwiseMin(hi)).norm();
}

}  // namespace

CarvedBody carveBody(const CarveInput& b, const std::vector<uint8_t>& remove) {
  checkInput(b);
  const VoxelVolume& old = *b.volume;
  const Layout& oldLayout = *b.layout;
  const RestModel& oldModel = *b.model;
  if (remove.size() != old.size()) throw std::invalid_argument("carve: the mask's size is not the volume's");
  const int D = oldLayout.dim;
  const Real h = oldLayout.voxelSize;
  CarvedBody out;
  out.volume = old;
  const std::vector<int32_t> owner = voxelOwners(oldLayout, old);

  // What leaves: each removed voxel's mass and its momentum at its centre.
  const auto& n = old.dims();
  for (int k = 0; k < n[2]; ++k)
    for (int j = 0; j < n[1]; ++j)
      for (int i = 0; i < n[0]; ++i) {
        const size_t q = old.index(i, j, k);
        if (!remove[q] || !old.at(i, j, k)) continue;
        const Real m = voxelMass(oldModel, old.label(i, j, k), h, D);
        const MassCell c = cellOfVoxel(oldLayout, size_t(owner[q]), Int3(i, j, k));
        const Vec3 centre(i + 0.5, j + 0.5, D == 3 ? k + 0.5 : 0.0);
        const Vec3 v = interpolate(c, trilinear(localPoint(c, centre), D), b.velocities);
        out.removedMass += m, out.removedMomentum += m * v, out.removedKineticEnergy += 0.5 * m * v.squaredNorm();
        out.volume.set(i, j, k, false);
        ++out.removedVoxels;
      }
  if (out.removedVoxels == old.countFilled()) {
    out.emptied = true;
    out.removedVoxels = 0, out.removedMass = 0, out.removedMomentum.setZero(), out.removedKineticEnergy = 0;
    out.volume = old;
  }
  out.removedVolume = Real(out.removedVoxels) * h * h * h;
  if (out.removedVoxels == 0) {
    out.layout = oldLayout;
    out.model = std::make_shared<const RestModel>(oldModel);
    out.positions.assign(b.positions, b.positions + oldModel.numVertices());
    out.velocities.assign(b.velocities, b.velocities + oldModel.numVertices());
    if (b.rotations)
      out.rotations.assign(b.rotations, b.rotations + oldModel.numElements());
    else
      out.rotations.assign(oldModel.numElements(), Quat::Identity());
    out.fromVertex.resize(oldModel.numVertices());
    for (uint32_t v = 0; v < out.fromVertex.size(); ++v) out.fromVertex[v] = v;
    return out;
  }

  // The new body: a full re-layout by the body's own rule and its rest model.
  out.layout = buildLayout(out.volume, oldLayout.kind);
  auto model = std::make_shared<RestModel>(buildRestModel(out.layout, out.volume, oldModel.material, oldModel.origin));
  const size_t V = out.layout.numVertices(), E = out.layout.numElements();
  out.positions.resize(V), out.velocities.resize(V), out.fromVertex.resize(V);
  for (size_t v = 0; v < V; ++v) {
    const Int3& p = out.layout.vertices[v];
    const uint32_t was = oldLayout.vertexAt(p);
    out.fromVertex[v] = was;
    if (was != Layout::kNoVertex) {
      out.positions[v] = b.positions[was], out.velocities[v] = b.velocities[was];
      continue;
    }
    // A new vertex: a corner of some filled voxel of the new volume (held by an old element).
    int32_t e = -1;
    Int3 q(0, 0, 0);
    for (int c = 0; c < cornerCount(D) && e < 0; ++c) {
      q = p - cornerOffset(c, D);
      if (out.volume.at(q.x(), q.y(), q.z())) e = owner[old.index(q.x(), q.y(), q.z())];
    }
    if (e < 0) throw std::logic_error("carve: a new vertex touches no voxel");
    const MassCell c = cellOfVoxel(oldLayout, size_t(e), q);
    const std::array<Real, 8> w = trilinear(localPoint(c, p.cast<Real>()), D);
    out.positions[v] = interpolate(c, w, b.positions), out.velocities[v] = interpolate(c, w, b.velocities);
    ++out.newVertices;
  }
  // Momentum: old - removed, the difference over the new vertices.
  Vec3 before = Vec3::Zero(), after = Vec3::Zero();
  Real newMass = 0;
  for (size_t v = 0; v < oldModel.numVertices(); ++v) before += oldModel.mass[v] * b.velocities[v];
  for (size_t v = 0; v < V; ++v) {
    after += model->mass[v] * out.velocities[v];
    if (out.fromVertex[v] == Layout::kNoVertex) newMass += model->mass[v];
  }
  if (newMass > 0) {
    out.momentumCorrection = (before - out.removedMomentum - after) / newMass;
    for (size_t v = 0; v < V; ++v)
      if (out.fromVertex[v] == Layout::kNoVertex) out.velocities[v] += out.momentumCorrection;
  }
  // Warm starts: the rotation of the old element at each new element's first filled cell.
  out.rotations.assign(E, Quat::Identity());
  if (b.rotations)
    for (size_t e = 0; e < E; ++e) {
      int c = 0;
      while (!(out.layout.cellMask[e] >> c & 1)) ++c;
      const Int3 q = out.layout.origin[e] + cornerOffset(c, D) * out.layout.cellSize[e];
      out.rotations[e] = b.rotations[owner[old.index(q.x(), q.y(), q.z())]];
    }
  out.model = std::move(model);
  return out;
}

std::vector<uint8_t> voxelsInSphere(const CarveInput& body, const Vec3& centre, Real radius, size_t* count) {
  return voxelsWhere(
      body, [&](const Vec3& lo, const Vec3& hi) { return boxDistance(centre, lo, hi) <= radius; },
      [&](const Vec3& x) { return (x - centre).squaredNorm() <= radius * radius; }, count);
}

std::vector<uint8_t> voxelsInCapsule(const CarveInput& body, const Vec3& from, const Vec3& to, Real radius,
                                     size_t* count) {
  const Vec3 d = to - from;
  const Real len2 = d.squaredNorm();
  auto distance = [&](const Vec3& x) {
    const Real t = len2 > 0 ? std::clamp((x - from).dot(d) / len2, Real(0), Real(1)) : Real(0);
    return (x - (from + t * d)).norm();
  };
  const Vec3 lo = from.cwiseMin(to), hi = from.cwiseMax(to);
  return voxelsWhere(
      body,
      [&](const Vec3& bmin, const Vec3& bmax) {
        return ((bmin - hi).cwiseMax(lo - bmax).cwiseMax(Vec3::Zero())).norm() <= radius;
      },
      [&](const Vec3& x) { return distance(x) <= radius; }, count);
}

std::vector<uint8_t> voxelsInCylinder(const CarveInput& body, const Vec3& from, const Vec3& to, const Vec3& axis,
                                      Real radius, Real halfLength, size_t* count) {
  if (!(axis.norm() > 0) || !axis.allFinite()) throw std::invalid_argument("carve: the cylinder's axis is zero");
  const Vec3 a = axis.normalized(), d = to - from;
  const Real along = d.dot(a);
  const Vec3 across = d - along * a;  // the move across the axis: the disc sweeps a stadium
  const Real across2 = across.squaredNorm();
  const Real zLo = std::min(Real(0), along) - halfLength, zHi = std::max(Real(0), along) + halfLength;
  auto inside = [&](const Vec3& x) {
    const Vec3 y = x - from;
    const Real z = y.dot(a);
    if (z < zLo || z > zHi) return false;
    const Vec3 p = y - z * a;
    const Real t = across2 > 0 ? std::clamp(p.dot(across) / across2, Real(0), Real(1)) : Real(0);
    return (p - t * across).squaredNorm() <= radius * radius;
  };
  // The cylinder's box (half extents per axis), at both ends of the move.
  Vec3 e;
  for (int k = 0; k < 3; ++k) e[k] = halfLength * std::abs(a[k]) + radius * std::sqrt(std::max(Real(0), 1 - a[k] * a[k]));
  const Vec3 lo = from.cwiseMin(to) - e, hi = from.cwiseMax(to) + e;
  return voxelsWhere(
      body, [&](const Vec3& bmin, const Vec3& bmax) { return (bmin.array() <= hi.array()).all() && (lo.array() <= bmax.array()).all(); },
      inside, count);
}

}  // namespace gradel
