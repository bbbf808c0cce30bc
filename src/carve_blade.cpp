// A blade's kerf (carve.h voxelsAlongBlade): the voxels whose deformed centres the swept
// rectangle passes within the kerf's half width.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <vector>

#include "carve_cells.h"
#include "gradel/carve.h"

namespace gradel {

namespace {

using namespace carve_cells;

// The moments t of [lo, hi] with |q0 - t dq| <= e (an interval, possibly empty: lo > hi).
void clipAbs(Real q0, Real dq, Real e, Real& lo, Real& hi) {
  if (dq == 0) {
    if (!(std::abs(q0) <= e)) lo = 1, hi = 0;
    return;
  }
  const Real a = (q0 - e) / dq, b = (q0 + e) / dq;
  lo = std::max(lo, std::min(a, b)), hi = std::min(hi, std::max(a, b));
}

}  // namespace

std::vector<uint8_t> voxelsAlongBlade(const CarveInput& b, const BladeSweep& blade, size_t* count) {
  checkInput(b);
  const Layout& layout = *b.layout;
  const VoxelVolume& volume = *b.volume;
  if (layout.dim != 3) throw std::invalid_argument("carve: a blade cuts 3D bodies only");
  for (const Vec3* a : {&blade.axis, &blade.widthAxis})
    if (!(a->norm() > 0) || !a->allFinite()) throw std::invalid_argument("carve: a blade's axis is zero");
  const Vec3 u = blade.axis.normalized(), w = blade.widthAxis.normalized();
  if (std::abs(u.dot(w)) > 1e-6) throw std::invalid_argument("carve: a blade's axes are not perpendicular");
  const Vec3 n = u.cross(w).normalized();
  const Vec3 d = blade.to - blade.from;
  const Real du = d.dot(u), dw = d.dot(w), dn = d.dot(n);
  const Real a = blade.halfLength, c = blade.halfWidth;
  // The swept rectangle's box (both ends), grown per cell by its kerf's half width.
  Vec3 ext;
  for (int k = 0; k < 3; ++k) ext[k] = a * std::abs(u[k]) + c * std::abs(w[k]);
  const Vec3 lo = blade.from.cwiseMin(blade.to) - ext, hi = blade.from.cwiseMax(blade.to) + ext;
  std::vector<uint8_t> mask(volume.size(), 0);
  size_t found = 0;
  forEachMassCell(layout, [&](size_t, const Int3& cellLo, int edge) {
    const MassCell cell = massCell(layout, cellLo, edge);
    const Vec3* x = b.positions;
    Vec3 bmin = x[cell.corner[0]], bmax = bmin;
    for (int k = 1; k < 8; ++k) bmin = bmin.cwiseMin(x[cell.corner[k]]), bmax = bmax.cwiseMax(x[cell.corner[k]]);
    // The cell's lattice frame: per axis the mean of its 4 edges, per voxel.
    Mat3 F = Mat3::Zero();
    for (int k = 0; k < 8; ++k)
      for (int ax = 0; ax < 3; ++ax)
        if (k >> ax & 1) F.col(ax) += (x[cell.corner[k]] - x[cell.corner[k ^ (1 << ax)]]) / (4.0 * edge);
    const Real half = 0.5 * (F.transpose() * n).cwiseAbs().sum();
    if ((bmax.array() < (lo.array() - half)).any() || (bmin.array() > (hi.array() + half)).any()) return;
    for (int k = 0; k < edge; ++k)
      for (int j = 0; j < edge; ++j)
        for (int i = 0; i < edge; ++i) {
          const Vec3 centre(cellLo.x() + i + 0.5, cellLo.y() + j + 0.5, cellLo.z() + k + 0.5);
          const Vec3 y = interpolate(cell, trilinear(localPoint(cell, centre), 3), x) - blade.from;
          const Real s = y.dot(u), r = y.dot(w), z = y.dot(n);
          Real t0 = 0, t1 = 1;
          clipAbs(s, du, a, t0, t1);
          clipAbs(r, dw, c, t0, t1);
          if (dn == 0) {
            if (!(-half < z && z <= half)) continue;
          } else {
            const Real p = (z - half) / dn, q = (z + half) / dn;
            t0 = std::max(t0, std::min(p, q)), t1 = std::min(t1, std::max(p, q));
          }
          if (!(t0 <= t1)) continue;
          uint8_t& m = mask[volume.index(cellLo.x() + i, cellLo.y() + j, cellLo.z() + k)];
          if (!m) m = 1, ++found;
        }
  });
  if (count) *count = found;
  return mask;
}

}  // namespace gradel
