// The body-contact stage's face grid (BodyContacts::Grid, body_contacts.h): the queries every
// phase reads (cell ranges, the faces a box meets, the nearest face of a point). Templates and
// the small inline lookups; the grid is built in body_contact_grid.cpp.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>

#include "body_contact_tracks.h"

namespace gradel {
namespace {

// A triangle whose box lies farther than this times the best squared distance so far (plus a
// tiny absolute slack) cannot be nearer than the best, nor as near: the slack covers rounding.
constexpr Real kPrune = 1 + 1e-9;

// Squared distance from p to a box (0 inside): a lower bound of the distance to what it holds.
Real boxDistance2(const Vec3& lo, const Vec3& hi, const Vec3& p) {
  return (lo - p).cwiseMax(p - hi).cwiseMax(Vec3::Zero()).squaredNorm();
}

}  // namespace

inline int64_t BodyContacts::Grid::cellOf(Real v, int a) const {
  return int64_t(std::clamp(std::floor((v - origin[a]) * inv), Real(0), Real(dims[size_t(a)] - 1)));
}

// The cell ranges of the query box [lo, hi] per axis; false when it misses every listed face.
inline bool BodyContacts::Grid::rangeOf(const Vec3& lo, const Vec3& hi, std::array<int64_t, 6>& c) const {
  if (count == 0 || (hi.array() < box.lo.array()).any() || (lo.array() > box.hi.array()).any()) return false;
  for (int a = 0; a < 3; ++a) c[size_t(a)] = cellOf(lo[a], a), c[size_t(a + 3)] = cellOf(hi[a], a);
  return true;
}

// Every listed face whose box meets the query box [lo, hi] (whatever the cells' size), once each,
// into q.candidates (indices into g.tri), then f(e) for each.
template <class F>
void BodyContacts::forCandidateTriangles(const Grid& g, const Vec3& lo, const Vec3& hi, QueryScratch& q, F&& f) const {
  q.candidates.clear();
  std::array<int64_t, 6> c;
  if (!g.rangeOf(lo, hi, c)) return;
  ++q.stamp;
  for (int64_t k = c[2]; k <= c[5]; ++k)
    for (int64_t j = c[1]; j <= c[4]; ++j) {
      // The cells of a row are adjacent in the table: one range of faces per row.
      const size_t row = size_t((k * g.dims[1] + j) * g.dims[0]);
      for (uint32_t i = g.start[row + size_t(c[0])]; i < g.start[row + size_t(c[3]) + 1]; ++i) {
        const uint32_t e = g.items[i];
        if (q.seen[e] == q.stamp) continue;
        q.seen[e] = q.stamp;
        const Box& tb = g.now.empty() ? g.triBox[e] : g.now[e];  // the face's box now, if kept
        if (!((tb.hi.array() < lo.array()).any() || (tb.lo.array() > hi.array()).any())) q.candidates.push_back(e);
      }
    }
  // In the cells' order: the callers break ties between equally near triangles by the lowest id.
  for (uint32_t e : q.candidates) f(e);
}

// The nearest listed face of `faces` to p closer than `reach` (ties: the lowest id), or kNone. The
// cell holding p first, then the others of the query box, skipping a cell (or a row, a plane of
// cells) that lies farther than the best so far, and a face whose box does: the face a point is
// nearest to is listed in the cell holding that nearest point, which is no farther than it. A
// face may be tested twice (it spans several cells): the same distance, no tie with itself.
// With `accept`: the nearest face for which accept(t, closest point) holds (asked only of a face
// nearer than the best so far, or as near with a lower id).
template <class Accept>
BodyContacts::Nearest BodyContacts::nearestTriangle(const Grid& g, const ContactBody& faces, const Vec3& p, Real reach,
                                                    const Vec3* x, uint32_t hint, Accept&& accept) const {
  Nearest n{reach * reach, ContactBody::kNone, {}};
  const Real slack2 = 1e-24 * faces.thickness * faces.thickness;  // rounding of a box beside a point on a face
  auto test = [&](uint32_t t) {
    const auto& tri = faces.triangles[t];
    const ClosestPoint cp = closestPointOnTriangle(p, x[tri[0]], x[tri[1]], x[tri[2]]);
    ++n.tests;
    const Vec3 c = cp.w[0] * x[tri[0]] + cp.w[1] * x[tri[1]] + cp.w[2] * x[tri[2]];
    const Real d2 = (p - c).squaredNorm();
    if ((d2 < n.d2 || (d2 == n.d2 && n.tri != ContactBody::kNone && t < n.tri)) && accept(t, c))
      n.d2 = d2, n.tri = t, n.cp = cp;
  };
  // A face known to be near (the last answer) bounds the search: the same answer, sooner.
  if (hint != ContactBody::kNone) test(hint);
  const Real qr = std::sqrt(n.d2 * kPrune + slack2);  // a face nearer than the best meets p +- qr
  std::array<int64_t, 6> c;
  if (!g.rangeOf(p - Vec3::Constant(qr), p + Vec3::Constant(qr), c)) return n;
  const Box* boxes = g.now.empty() ? g.triBox.data() : g.now.data();  // the faces' boxes now, if kept
  auto visit = [&](size_t cell) {
    for (uint32_t i = g.start[cell]; i < g.start[cell + 1]; ++i) {
      const uint32_t e = g.items[i];
      if (boxDistance2(boxes[e].lo, boxes[e].hi, p) > n.d2 * kPrune + slack2) continue;  // cannot be nearer (nor tie)
      test(g.tri[e]);
    }
  };
  const int64_t cells = (c[3] - c[0] + 1) * (c[4] - c[1] + 1) * (c[5] - c[2] + 1);
  constexpr int64_t kCells = 27;
  if (cells > kCells) {  // many cells (a grid finer than the reach): each unless farther than the best so far
    for (int64_t k = c[2]; k <= c[5]; ++k)
      for (int64_t j = c[1]; j <= c[4]; ++j)
        for (int64_t i = c[0]; i <= c[3]; ++i) {
          const size_t cell = size_t((k * g.dims[1] + j) * g.dims[0] + i);
          if (boxDistance2(g.cellBox[cell].lo, g.cellBox[cell].hi, p) <= n.d2 * kPrune + slack2) visit(cell);
        }
    return n;
  }
  // The cells of the query box by the distance of their boxes, the nearest one first.
  Real orderD2[kCells];  // (uninitialised: only the first m are read)
  uint32_t orderCell[kCells];
  size_t m = 0, first = 0;
  for (int64_t k = c[2]; k <= c[5]; ++k)
    for (int64_t j = c[1]; j <= c[4]; ++j)
      for (int64_t i = c[0]; i <= c[3]; ++i) {
        const size_t cell = size_t((k * g.dims[1] + j) * g.dims[0] + i);
        const Real d2 = boxDistance2(g.cellBox[cell].lo, g.cellBox[cell].hi, p);
        if (!(d2 <= n.d2 * kPrune + slack2)) continue;  // farther than the reach, or empty
        if (m == 0 || d2 < orderD2[first]) first = m;
        orderD2[m] = d2, orderCell[m++] = uint32_t(cell);
      }
  if (m == 0) return n;
  visit(orderCell[first]);
  for (size_t q = 0; q < m; ++q)
    if (q != first && orderD2[q] <= n.d2 * kPrune + slack2) visit(orderCell[q]);
  return n;
}

}  // namespace gradel
