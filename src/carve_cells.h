// The lattice kernels that carving (carve.cpp) and splitting a body into its pieces (pieces.cpp)
// share: a layout's mass cells (material.h: the boxes whose lumped mass goes to their corners),
// trilinear interpolation of a field over a cell's corners, which old element held each voxel,
// and the state carried from an old layout to a new one over the same lattice (carve.h, "State
// transfer"). Pure functions of their arguments.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

#include "gradel/carve.h"
#include "gradel/layout.h"
#include "gradel/model.h"
#include "gradel/volume.h"

namespace gradel::carve_cells {

/// A mass cell of a layout: element e's block when full, else one filled cell; it gives its mass
/// to its 2^dim corners, which are model vertices.
struct MassCell {
  Int3 lo{0, 0, 0};
  int edge = 1;  ///< [voxels]
  std::array<uint32_t, 8> corner{};
  int corners = 8;
};

inline int cornerCount(int dim) { return dim == 3 ? 8 : 4; }
inline Int3 cornerOffset(int k, int dim) { return Int3(k & 1, (k >> 1) & 1, dim == 3 ? (k >> 2) & 1 : 0); }

/// Calls f(e, lo, edge) for every mass cell of the layout, in element order.
template <class F>
void forEachMassCellOf(const Layout& layout, size_t e, F&& f) {
  const int cs = layout.cellSize[e];
  if (layout.isFull(e)) return f(e, layout.origin[e], 2 * cs);
  for (int c = 0; c < cornerCount(layout.dim); ++c)
    if (layout.cellMask[e] >> c & 1) f(e, Int3(layout.origin[e] + cornerOffset(c, layout.dim) * cs), cs);
}

template <class F>
void forEachMassCell(const Layout& layout, F&& f) {
  for (size_t e = 0; e < layout.numElements(); ++e) forEachMassCellOf(layout, e, f);
}

/// The cell of edge `edge` at `lo` with its corners' vertex ids (std::logic_error if one is not a vertex).
MassCell massCell(const Layout& layout, const Int3& lo, int edge);

/// Trilinear weights of the local point t in [0, 1]^dim.
std::array<Real, 8> trilinear(const Vec3& t, int dim);

template <class T>
T interpolate(const MassCell& c, const std::array<Real, 8>& w, const T* values) {
  T s = T::Zero();
  for (int k = 0; k < c.corners; ++k) s += w[k] * values[c.corner[k]];
  return s;
}

inline Vec3 localPoint(const MassCell& c, const Vec3& latticePoint) {
  return (latticePoint - c.lo.cast<Real>()) / Real(c.edge);
}

/// Per voxel (storage order), the element holding it (-1: empty).
std::vector<int32_t> voxelOwners(const Layout& layout, const VoxelVolume& volume);

/// The mass cell of element e holding voxel q.
MassCell cellOfVoxel(const Layout& layout, size_t e, const Int3& q);

/// The state of a body over an old layout carried to a new layout of (a part of) the same
/// lattice (carve.h, "State transfer").
struct Transferred {
  std::vector<Vec3> positions, velocities;
  std::vector<Quat> rotations;
  std::vector<uint32_t> fromVertex;  ///< Per new vertex: its old id, or Layout::kNoVertex.
  size_t newVertices = 0;
  Vec3 momentumCorrection{0, 0, 0};  ///< [m/s] added to every new vertex's interpolated velocity.
};

/// Moves a transfer into a carved body or a piece (CarveResult, BodyPiece: the same fields).
template <class Body>
void takeTransferred(Body& out, Transferred&& t) {
  out.positions = std::move(t.positions), out.velocities = std::move(t.velocities);
  out.rotations = std::move(t.rotations), out.fromVertex = std::move(t.fromVertex);
  out.newVertices = t.newVertices, out.momentumCorrection = t.momentumCorrection;
}

/// Surviving vertices (same lattice point) keep position and velocity bit for bit; a new vertex
/// takes the trilinear interpolation over the old mass cell (owner[] of the old layout) of a
/// voxel of `volume` it is a corner of; rotations from the old element at each new element's
/// first filled cell (identity when `oldRotations` is null). The new vertices then share one
/// velocity correction so that the new momentum is `targetMomentum` (formed as target - after).
Transferred transferState(const Layout& oldLayout, const std::vector<int32_t>& owner, const VoxelVolume& oldVolume,
                          const Vec3* oldPositions, const Vec3* oldVelocities, const Quat* oldRotations,
                          const VoxelVolume& volume, const Layout& layout, const RestModel& model,
                          const Vec3& targetMomentum);

/// std::invalid_argument for null inputs or a model that is not the layout's.
void checkInput(const CarveInput& b);

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
  // An element whose vertices' box is not near: none of its cells' boxes (within it) is.
  for (size_t e = 0; e < layout.numElements(); ++e) {
    Vec3 emin = b.positions[layout.elemVerts[layout.elemStart[e]]], emax = emin;
    for (uint32_t p = layout.elemStart[e] + 1; p < layout.elemStart[e + 1]; ++p)
      emin = emin.cwiseMin(b.positions[layout.elemVerts[p]]), emax = emax.cwiseMax(b.positions[layout.elemVerts[p]]);
    if (near(emin, emax)) forEachMassCellOf(layout, e, [&](size_t, const Int3& lo, int edge) {
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
  }
  if (count) *count = n;
  return mask;
}

}  // namespace gradel::carve_cells
