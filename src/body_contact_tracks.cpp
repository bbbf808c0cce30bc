// Broad phase of the body-contact stage, kept across steps: per ordered pair of bodies a track,
// b's faces that can come within rCap of a's surface before the next rebuild (in a grid) and a's
// candidate vertices; every track rebuilt when a surface moved more than loose since the rebuild
// or a pair's search radius passed rCap (docs/speed.md, "Body contacts: the stage").
#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "body_contact_grid.h"
#include "body_contact_tuning.h"
#include "gradel/body_contacts.h"

namespace gradel {

// Whether every track still holds: no surface farther than loose_ from the rebuild, no pair's
// search radius over rCap_.
bool BodyContacts::tracksHold() const {
  if (!tracksValid_) return false;
  const size_t B = bodies_.size();
  for (size_t a = 0; a < B; ++a) {
    if (!(sinceAxis_[a] <= loose_)) return false;
    for (size_t b = 0; b < B; ++b)
      if (a != b && !(searchRadius(a, b) <= rCap_)) return false;
  }
  return true;
}

// Every track from the positions x: each body's surface as it is now (the reference its motion
// is measured from), the boxes of its blocks of vertices and of its patches of faces, then per
// ordered pair its faces and candidate vertices.
void BodyContacts::rebuildTracks(const Vec3* x) {
  const size_t B = bodies_.size();
  Real r = 0, thickest = 0;
  for (size_t a = 0; a < B; ++a) {
    thickest = std::max(thickest, bodies_[a].thickness);
    for (size_t b = 0; b < B; ++b)
      if (a != b) r = std::max(r, searchRadius(a, b));
  }
  rCap_ = r + kRadiusSlack * thickest;
  for (size_t b = 0; b < B; ++b) {
    const ContactBody& body = bodies_[b];
    Box all;
    for (uint32_t k = blockStart_[b]; k < blockStart_[b + 1]; ++k) {
      const uint32_t i0 = (k - blockStart_[b]) * kBoundsBlock;
      const uint32_t i1 = std::min<uint32_t>(i0 + kBoundsBlock, uint32_t(body.vertices.size()));
      Box box;
      for (uint32_t i = i0; i < i1; ++i) {
        box.add(x[body.vertices[i]]);
      }
      blockBox_[k] = box;
      all.add(box);
    }
    bounds_[b] = all;
    Vec3 rounding = Vec3::Zero();
    for (uint32_t u = body.vertexBegin; u < body.vertexEnd; ++u) {
      ref_[u] = {float(x[u].x()), float(x[u].y()), float(x[u].z()), 0.f};
      for (int a = 0; a < 3; ++a)
        rounding[a] = std::max(rounding[a], std::abs(Real(ref_[u][size_t(a)]) - x[u][a]));  // (NaN: left out)
    }
    refRounding_[b] = rounding;
    sinceRebuild_[b] = sinceRebuildStart_[b] = sinceAxis_[b] = sinceAxisStart_[b] = 0;
  }
  updatePatches(x);
  for (size_t a = 0; a < B; ++a)
    for (size_t b = 0; b < B; ++b)
      if (a != b) buildTrack(a, b, x);
  tracksValid_ = true;
}

namespace {
bool meets(const Vec3& lo0, const Vec3& hi0, const Vec3& lo1, const Vec3& hi1) {
  return !((hi0.array() < lo1.array()).any() || (lo0.array() > hi1.array()).any());
}
}  // namespace

// The track of a's vertices against b's faces: the faces whose box, grown by how far they may
// move (loose_), reaches within rCap_ + loose_ of a's surface, in a grid; the vertices of a whose
// point, grown by that, meets one of their boxes (any other vertex stays farther than rCap_ from
// every face of b until the next rebuild: it moves at most loose_, the faces stay in their boxes).
void BodyContacts::buildTrack(size_t a, size_t b, const Vec3* x) {
  Track& T = tracks_[a * bodies_.size() + b];
  T.vertices.clear(), T.clearance.clear(), T.checkedAt.clear(), T.faceDrift.clear();
  T.faceCorrected.clear(), T.checkedStage.clear(), T.checkedRound.clear();
  T.roundClearance.clear(), T.roundAt.clear(), T.roundStage.clear(), T.roundOf.clear();
  T.grid.count = 0, T.grid.tri.clear(), T.grid.triBox.clear();
  const ContactBody& A = bodies_[a];
  const ContactBody& F = bodies_[b];
  const Real reach = loose_ + rCap_;
  const Vec3 qlo = bounds_[a].lo - Vec3::Constant(reach), qhi = bounds_[a].hi + Vec3::Constant(reach);
  const Vec3 flo = bounds_[b].lo - Vec3::Constant(loose_), fhi = bounds_[b].hi + Vec3::Constant(loose_);
  if (!meets(qlo, qhi, flo, fhi)) return;
  const Box region{qlo.cwiseMax(flo), qhi.cwiseMin(fhi)};
  std::vector<uint32_t> subset;  // the faces of the patches near the region
  const Patches& P = patches_[b];
  for (size_t k = 0; k < P.box.size(); ++k) {
    if (!meets(P.box[k].lo - Vec3::Constant(loose_), P.box[k].hi + Vec3::Constant(loose_), region.lo, region.hi))
      continue;
    for (size_t j = k * kPatch; j < std::min(P.tris.size(), (k + 1) * kPatch); ++j) subset.push_back(P.tris[j]);
  }
  std::sort(subset.begin(), subset.end());  // listing order: by id
  buildGrid(T.grid, F, region, x, &subset, kTrackCell * std::max(A.thickness, F.thickness), loose_);
  const Grid& g = T.grid;
  if (g.count == 0) return;
  const Vec3 nlo = g.box.lo - Vec3::Constant(reach), nhi = g.box.hi + Vec3::Constant(reach);
  for (uint32_t k = blockStart_[a]; k < blockStart_[a + 1]; ++k) {
    if (!meets(blockBox_[k].lo, blockBox_[k].hi, nlo, nhi)) continue;
    const uint32_t i0 = (k - blockStart_[a]) * kBoundsBlock;
    const uint32_t i1 = std::min<uint32_t>(i0 + kBoundsBlock, uint32_t(A.vertices.size()));
    for (uint32_t i = i0; i < i1; ++i) {
      const Vec3& p = x[A.vertices[i]];
      const Vec3 lo = p - Vec3::Constant(reach), hi = p + Vec3::Constant(reach);
      std::array<int64_t, 6> c;
      if (!g.rangeOf(lo, hi, c)) continue;
      bool hit = false;
      for (int64_t kz = c[2]; kz <= c[5] && !hit; ++kz)
        for (int64_t j = c[1]; j <= c[4] && !hit; ++j) {
          const size_t row = size_t((kz * g.dims[1] + j) * g.dims[0]);
          for (uint32_t e = g.start[row + size_t(c[0])]; e < g.start[row + size_t(c[3]) + 1] && !hit; ++e)
            hit = meets(g.triBox[g.items[e]].lo, g.triBox[g.items[e]].hi, lo, hi);
        }
      if (!hit) continue;
      T.vertices.push_back(i);
      T.clearance.push_back(-1);  // look it up at its first check
      T.checkedAt.push_back(p);
      T.faceDrift.push_back(0);
      T.faceCorrected.push_back(0);
      T.checkedStage.push_back(stage_ - 1);
      T.checkedRound.push_back(0);
      T.roundClearance.push_back(-1), T.roundAt.push_back(p), T.roundStage.push_back(stage_ - 1),
          T.roundOf.push_back(0);
    }
  }
}

// The bodies' triangles in patches of kPatch near each other (built at the first call, in the
// Morton order of their centres then: any order gives the same result, a compact one fewer
// patches to visit) and each patch's box now.
void BodyContacts::updatePatches(const Vec3* x) {
  if (patches_.empty()) {
    patches_.resize(bodies_.size());
    std::vector<std::pair<uint64_t, uint32_t>> keyed;
    for (size_t b = 0; b < bodies_.size(); ++b) {
      const ContactBody& body = bodies_[b];
      Patches& P = patches_[b];
      Vec3 lo = Vec3::Constant(std::numeric_limits<Real>::infinity());
      for (uint32_t u : body.vertices)
        if (x[u].allFinite()) lo = lo.cwiseMin(x[u]);
      keyed.clear();
      for (uint32_t t = 0; t < body.triangles.size(); ++t) {
        const auto& tri = body.triangles[t];
        const Vec3 c = (x[tri[0]] + x[tri[1]] + x[tri[2]] - 3 * lo) / (3 * body.thickness);
        uint64_t key = 0;
        if (c.allFinite())
          for (int bit = 20; bit >= 0; --bit)
            for (int a = 2; a >= 0; --a) {
              const uint64_t q = uint64_t(std::clamp(c[a], Real(0), Real((1 << 21) - 1)));
              key = key << 1 | (q >> bit & 1);
            }
        keyed.push_back({key, t});
      }
      std::sort(keyed.begin(), keyed.end());
      P.tris.clear(), P.vertStart.assign(1, 0), P.verts.clear();
      for (const auto& k : keyed) P.tris.push_back(k.second);
      for (size_t j0 = 0; j0 < P.tris.size(); j0 += kPatch) {
        const size_t first = P.verts.size();
        for (size_t j = j0; j < std::min(P.tris.size(), j0 + kPatch); ++j)
          for (uint32_t u : body.triangles[P.tris[j]]) P.verts.push_back(u);
        std::sort(P.verts.begin() + long(first), P.verts.end());
        P.verts.erase(std::unique(P.verts.begin() + long(first), P.verts.end()), P.verts.end());
        P.vertStart.push_back(uint32_t(P.verts.size()));
      }
      P.box.resize(P.vertStart.size() - 1);
    }
  }
  for (Patches& P : patches_)
    for (size_t k = 0; k + 1 < P.vertStart.size(); ++k) {
      Box box;
      for (uint32_t j = P.vertStart[k]; j < P.vertStart[k + 1]; ++j) box.add(x[P.verts[j]]);
      P.box[k] = box;
    }
}

}  // namespace gradel
