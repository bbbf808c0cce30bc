// The body-contact stage's face grid (body_contact_grid.h): its build and the members' scratch.
#include "body_contact_grid.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "thread_team.h"

namespace gradel {

// A grid of a body's faces: the faces whose box, grown by `grow`, meets `region` (all of them,
// or those of `subset`, in its order), in a dense table of cells over the box they fill within
// the region (cell -> its faces, in listing order): a query reads its cells' ranges directly.
// Which cells a face is in never changes a result: a face within reach of a point is in the
// cells of the point's query box, whatever their size.
void BodyContacts::buildGrid(Grid& g, const ContactBody& faces, const Box& region, const Vec3* x,
                             const std::vector<uint32_t>* subset, Real reach, Real grow) {
  g.tri.clear(), g.triBox.clear();
  Box filled;
  auto add = [&](uint32_t t) {
    const auto& tri = faces.triangles[t];
    const Vec3 lo = x[tri[0]].cwiseMin(x[tri[1]]).cwiseMin(x[tri[2]]) - Vec3::Constant(grow);
    const Vec3 hi = x[tri[0]].cwiseMax(x[tri[1]]).cwiseMax(x[tri[2]]) + Vec3::Constant(grow);
    if ((hi.array() < region.lo.array()).any() || (lo.array() > region.hi.array()).any()) return;
    if (!lo.allFinite() || !hi.allFinite()) return;
    g.tri.push_back(t);
    g.triBox.push_back({lo, hi});
    filled.add(Box{lo.cwiseMax(region.lo), hi.cwiseMin(region.hi)});
  };
  if (subset)
    for (uint32_t t : *subset) add(t);
  else
    for (uint32_t t = 0; t < faces.triangles.size(); ++t) add(t);
  g.count = 0;
  if (g.tri.empty()) return;
  g.box = filled, g.origin = filled.lo;
  // Cells of twice the reach (a query's box then spans at most 2 cells per axis; measured: finer
  // cells cost more to fill than they save the queries), coarser if there would be more than
  // ~8 cells per listed face.
  const Vec3 extent = filled.hi - filled.lo;
  const double cellsMax = std::max(4096.0, 8.0 * double(g.tri.size()));
  g.cell = std::max(2 * reach, extent.maxCoeff() * Real(1e-6));
  for (;;) {
    double cells = 1;
    for (int a = 0; a < 3; ++a) cells *= std::floor(extent[a] / g.cell) + 1;
    if (cells <= cellsMax) break;
    g.cell *= Real(1.25);
  }
  g.inv = 1 / g.cell;
  for (int a = 0; a < 3; ++a) g.dims[size_t(a)] = int64_t(std::floor(extent[a] * g.inv)) + 1;
  g.count = size_t(g.dims[0] * g.dims[1] * g.dims[2]);
  g.start.assign(g.count + 1, 0);
  g.range.resize(g.tri.size());
  for (size_t e = 0; e < g.tri.size(); ++e) {  // counts per cell, then offsets, then the faces in listing order
    const Box& tb = g.triBox[e];
    std::array<int32_t, 6>& c = g.range[e];
    for (int a = 0; a < 3; ++a)
      c[size_t(a)] = int32_t(g.cellOf(tb.lo[a], a)), c[size_t(a + 3)] = int32_t(g.cellOf(tb.hi[a], a));
    for (int64_t k = c[2]; k <= c[5]; ++k)
      for (int64_t j = c[1]; j <= c[4]; ++j)
        for (int64_t i = c[0]; i <= c[3]; ++i) ++g.start[size_t((k * g.dims[1] + j) * g.dims[0] + i) + 1];
  }
  for (size_t i = 0; i < g.count; ++i) g.start[i + 1] += g.start[i];
  g.items.resize(g.start[g.count]);
  g.fill.assign(g.start.begin(), g.start.end() - 1);
  g.cellBox.assign(g.count, Box{});
  // A cell's box: its faces' boxes clipped to the cell (grown by a rounding slack; the outer cells
  // unclipped outwards), which holds the nearest point of any of them that lies in the cell.
  const Real slack = Real(1e-6) * g.cell;
  for (int a = 0; a < 3; ++a) {
    std::vector<Real>&lo = g.cellLo[size_t(a)], &hi = g.cellHi[size_t(a)];
    const int64_t n = g.dims[size_t(a)];
    lo.resize(size_t(n)), hi.resize(size_t(n));
    for (int64_t i = 0; i < n; ++i) {
      lo[size_t(i)] = i == 0 ? -std::numeric_limits<Real>::infinity() : g.origin[a] + Real(i) * g.cell - slack;
      hi[size_t(i)] = i + 1 == n ? std::numeric_limits<Real>::infinity() : g.origin[a] + Real(i + 1) * g.cell + slack;
    }
  }
  for (size_t e = 0; e < g.tri.size(); ++e) {
    const std::array<int32_t, 6>& c = g.range[e];
    const Box& tb = g.triBox[e];
    for (int64_t k = c[2]; k <= c[5]; ++k) {
      const Real zlo = std::max(tb.lo.z(), g.cellLo[2][size_t(k)]), zhi = std::min(tb.hi.z(), g.cellHi[2][size_t(k)]);
      for (int64_t j = c[1]; j <= c[4]; ++j) {
        const Real ylo = std::max(tb.lo.y(), g.cellLo[1][size_t(j)]), yhi = std::min(tb.hi.y(), g.cellHi[1][size_t(j)]);
        for (int64_t i = c[0]; i <= c[3]; ++i) {
          const size_t cell = size_t((k * g.dims[1] + j) * g.dims[0] + i);
          g.items[g.fill[cell]++] = uint32_t(e);
          const Vec3 lo(std::max(tb.lo.x(), g.cellLo[0][size_t(i)]), ylo, zlo);
          const Vec3 hi(std::min(tb.hi.x(), g.cellHi[0][size_t(i)]), yhi, zhi);
          g.cellBox[cell].add(Box{lo, hi});
        }
      }
    }
  }
}

// The dedupe stamps of every member, sized for grid g's faces.
void BodyContacts::prepareScratch(const Grid& g) {
  const size_t members = team_ ? size_t(team_->members()) : 1;
  if (scratch_.size() < members) scratch_.resize(members);
  for (QueryScratch& q : scratch_)
    if (q.seen.size() < g.tri.size()) q.seen.assign(g.tri.size(), q.stamp);
}

BodyContacts::Nearest BodyContacts::nearestTriangle(const Grid& g, const ContactBody& faces, const Vec3& p, Real reach,
                                                    const Vec3* x, uint32_t hint) const {
  return nearestTriangle(g, faces, p, reach, x, hint, [](uint32_t, const Vec3&) { return true; });
}

}  // namespace gradel
