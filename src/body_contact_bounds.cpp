// Broad phase of the body-contact stage, per step and round: how far each body's surface moved
// (BodyMotion), and which of a track's candidates may have reached the other body's surface since
// their last check (the rest are outside: not looked up). docs/speed.md, "Body contacts: the stage".
#include <algorithm>
#include <cmath>
#include <limits>

#include "body_contact_grid.h"
#include "body_contact_tuning.h"
#include "gradel/body_contacts.h"
#include "thread_team.h"

namespace gradel {

// The search radius of a pair: about a voxel plus how far both surfaces moved in the step (a
// vertex that started the step outside cannot end it deeper than that).
Real BodyContacts::searchRadius(size_t a, size_t b) const {
  return std::max(bodies_[a].thickness, bodies_[b].thickness) + moved_[a] + moved_[b];
}

// The bounds of a body's motion from its BodyMotion: how far its surface moved in the step and
// since the rebuild (Euclidean: at most the root of the sum of the axes' largest squares) and the
// latter per axis (the largest of them: what keeps a face in its box, tracksHold).
void BodyContacts::setMotion(size_t b, const BodyMotion& m) {
  moved_[b] = std::sqrt(m.moved2[0] + m.moved2[1] + m.moved2[2]);
  // From the rounded positions of the rebuild: at most the rounding farther per axis.
  Vec3 since;
  for (int a = 0; a < 3; ++a) since[a] = std::sqrt(m.since2[size_t(a)]) + refRounding_[b][a];
  sinceRebuild_[b] = tracksValid_ ? since.norm() : 0;
  sinceAxis_[b] = tracksValid_ ? since.maxCoeff() : 0;
}

// Per body, one pass over its vertices (BodyMotion; what an explicit step measures in its own
// vertex pass and hands in: BodyContactState::motion).
void BodyContacts::measure(const BodyContactState& s) {
  // In chunks of kMeasureChunk vertices (on the team's members when there are many), each chunk's
  // maxima into its own slot: max is exact, so the result is the same at any thread count.
  const size_t B = bodies_.size();
  const uint32_t chunks = chunkStart_.back();
  auto one = [&](uint32_t c) {
    const size_t b = size_t(std::upper_bound(chunkStart_.begin(), chunkStart_.end(), c) - chunkStart_.begin()) - 1;
    const size_t i0 = bodies_[b].vertexBegin + size_t(c - chunkStart_[b]) * kMeasureChunk;
    BodyMotion m;
    addMotion(s.positions, s.previousPositions, ref_.data(), i0,
              std::min<size_t>(bodies_[b].vertexEnd, i0 + kMeasureChunk), m);
    chunkMotion_[c] = m;
  };
  forEachInChunks(chunks >= 4 ? team_ : nullptr, chunks, 1, [&](size_t c) { one(uint32_t(c)); });
  for (size_t b = 0; b < B; ++b) {
    BodyMotion m;
    for (uint32_t c = chunkStart_[b]; c < chunkStart_[b + 1]; ++c) m.add(chunkMotion_[c]);
    setMotion(b, m);
  }
}

// Broad phase: how far each body's surface moved in the step and since the tracks' rebuild
// (round 0: one pass over the surfaces; a later round adds what the corrections moved since).
void BodyContacts::measureRound(const BodyContactState& s, int round) {
  const Vec3* x = s.positions;
  const size_t B = bodies_.size();
  if (round == 0) {
    if (s.motion && useGivenMotion_) {
      for (size_t b = 0; b < B; ++b) setMotion(b, s.motion[b]);
    } else {
      measure(s);
    }
    movedStart_ = moved_, sinceRebuildStart_ = sinceRebuild_, sinceAxisStart_ = sinceAxis_;
    corrected_.assign(B, 0);
  } else {  // only the vertices of the contacts moved since
    moved_ = movedStart_, sinceRebuild_ = sinceRebuildStart_, sinceAxis_ = sinceAxisStart_;
    auto grow = [](Real& to, Real d) {
      to = std::isnan(d) ? std::numeric_limits<Real>::infinity() : std::max(to, d);
    };
    for (size_t k = 0; k < touched_.size(); ++k) {
      const uint32_t u = touched_[k], b = bodyOf_[u];
      grow(moved_[b], (x[u] - s.previousPositions[u]).norm());
      const RefPoint& q = ref_[u];
      const Vec3 d = (x[u] - Vec3(q[0], q[1], q[2])).cwiseAbs() + refRounding_[b];
      grow(sinceRebuild_[b], d.norm());
      grow(sinceAxis_[b], d.hasNaN() ? std::numeric_limits<Real>::quiet_NaN() : d.cwiseAbs().maxCoeff());
      grow(corrected_[b], (x[u] - touchedStart_[k]).norm());
    }
    // What the last round's corrections moved (a vertex found then sat where it was at the
    // stage's start until its first correction): the local bound of the skips (shiftCells).
    roundShiftMax_.assign(B, 0);
    for (size_t k = 0; k < touched_.size(); ++k) {
      const uint32_t u = touched_[k];
      roundShift_[u] = (x[u] - touchedLast_[k]).norm();
      if (std::isnan(roundShift_[u])) roundShift_[u] = std::numeric_limits<Real>::infinity();
      roundShiftMax_[bodyOf_[u]] = std::max(roundShiftMax_[bodyOf_[u]], roundShift_[u]);
      touchedLast_[k] = x[u];
    }
  }
}

// After the first round only the pairs with a body that a correction of the round before
// moved: a contact of a's vertices against b's faces moves vertices of both, so it can push
// a vertex of b into a face of a (pair (b, a)) or into a third body's faces as well.
void BodyContacts::pickPairs(bool onlyMoved) {
  const size_t B = bodies_.size();
  movedBodies_.assign(B, 0);
  for (size_t a = 0; a < B; ++a)
    for (size_t b = 0; b < B; ++b)
      if (active_[a * B + b]) movedBodies_[a] = movedBodies_[b] = 1;
  pick_.assign(B * B, 0);
  for (size_t a = 0; a < B; ++a)
    for (size_t b = 0; b < B; ++b) {
      if (a == b && !settings_.selfContact) continue;
      if (onlyMoved && !movedBodies_[a] && !movedBodies_[b]) {
        active_[a * B + b] = 0;
        continue;
      }
      pick_[a * B + b] = 1;
    }
}

// A contact's vertices may move from now on (the only ones a correction moves): remember where
// they were when the stage began (no correction has moved them yet).
void BodyContacts::markTouched(const Contact& c, const Vec3* x, const Vec3* v) {
  auto mark = [&](uint32_t u) {
    if (isTouched_[u]) return;
    isTouched_[u] = 1;
    touched_.push_back(u);
    touchedStart_.push_back(x[u]);
    touchedLast_.push_back(x[u]);
    touchedStartV_.push_back(v[u]);
  };
  mark(c.vertex);
  for (uint32_t u : c.face) mark(u);
}

// The cells of pair (a, b)'s grid that a face of b moved by the last round's corrections may
// reach: a face whose corners moved at most e (the largest of their roundShift_) is within e of
// where it was; a vertex of a within e_a (roundShiftMax_[a]). A vertex checked then at clearance
// c that moved d <= e_a since is still outside if every such face has e + d < c or lies farther
// than e + d from it now (along the straight paths from then to now neither reached the other):
// each face's box now, grown by e + e_a + margin, marks its cells with e (cellShift_; a box
// reaching out of the grid's box: outsideShift_), and a vertex's cell bounds the faces that can
// have reached it. Its distance to b's surface is then at least c - d - (its cell's e) from the
// faces that moved by e and the others, and at least `margin` from the moved faces not marked in
// its cell. False when a face is not finite (then no cell bounds anything).
bool BodyContacts::shiftCells(size_t a, size_t b, const Vec3* x, Real margin) {
  const Grid& g = tracks_[a * bodies_.size() + b].grid;
  const ContactBody& F = bodies_[b];
  if (cellShift_.size() < g.count) cellShift_.resize(g.count, 0);
  cellShiftSet_.clear();
  outsideShift_ = 0;
  const Real ea = roundShiftMax_[a];
  // Each face once, though up to three of its corners moved (the marks are maxima: order-free).
  if (shiftSeen_.size() < F.triangles.size()) shiftSeen_.assign(F.triangles.size(), 0), shiftStamp_ = 0;
  if (++shiftStamp_ == 0) std::fill(shiftSeen_.begin(), shiftSeen_.end(), 0), shiftStamp_ = 1;
  for (uint32_t u : touched_) {
    if (bodyOf_[u] != b || !(roundShift_[u] > 0)) continue;
    const uint32_t s = F.surfaceIndex(u);
    for (uint32_t j = F.vertexTriStart[s]; j < F.vertexTriStart[s + 1]; ++j) {
      if (shiftSeen_[F.vertexTris[j]] == shiftStamp_) continue;
      shiftSeen_[F.vertexTris[j]] = shiftStamp_;
      const auto& t = F.triangles[F.vertexTris[j]];
      const Real e = std::max({roundShift_[t[0]], roundShift_[t[1]], roundShift_[t[2]]});
      const Vec3 grow = Vec3::Constant(e + ea + margin);
      const Vec3 lo = x[t[0]].cwiseMin(x[t[1]]).cwiseMin(x[t[2]]) - grow;
      const Vec3 hi = x[t[0]].cwiseMax(x[t[1]]).cwiseMax(x[t[2]]) + grow;
      if (!lo.allFinite() || !hi.allFinite()) {
        for (uint32_t cell : cellShiftSet_) cellShift_[cell] = 0;
        return false;
      }
      if (!(lo.array() >= g.box.lo.array()).all() || !(hi.array() <= g.box.hi.array()).all())
        outsideShift_ = std::max(outsideShift_, e);
      std::array<int64_t, 6> c;
      for (int k = 0; k < 3; ++k) c[size_t(k)] = g.cellOf(lo[k], k), c[size_t(k + 3)] = g.cellOf(hi[k], k);
      for (int64_t kz = c[2]; kz <= c[5]; ++kz)
        for (int64_t ky = c[1]; ky <= c[4]; ++ky)
          for (int64_t kx = c[0]; kx <= c[3]; ++kx) {
            const uint32_t cell = uint32_t((kz * g.dims[1] + ky) * g.dims[0] + kx);
            if (cellShift_[cell] == 0) cellShiftSet_.push_back(cell);
            cellShift_[cell] = std::max(cellShift_[cell], e);
          }
    }
  }
  return true;
}

// Surface vertices of body a against the faces of body b (the pseudo-normal test, see the header),
// from the pair's track: only its candidates, and of those only the ones that may have reached b's
// surface since their last check (they were at least `clearance` from it then; since, the vertex
// moved what it moved and b's faces at most sinceRebuild_[b] plus what they had moved then). Lists
// them (looked_, lookedJob_) as a job of the round's batch (detectPairs).
void BodyContacts::preparePair(size_t a, size_t b, const BodyContactState& s) {
  Track& T = tracks_[a * bodies_.size() + b];
  PairJob job{uint32_t(a), uint32_t(b), 0, false, 0, 0, uint32_t(looked_.size()), uint32_t(looked_.size())};
  if (T.grid.count == 0 || T.vertices.empty()) return jobs_.push_back(job);
  const ContactBody& A = bodies_[a];
  const ContactBody& B = bodies_[b];
  job.r = searchRadius(a, b);
  job.smallStep = movedStart_[a] + movedStart_[b] <= kSmallStep * std::max(A.thickness, B.thickness);
  job.faceMoved = sinceRebuild_[b], job.faceCorrected = corrected_[b];
  const Vec3* x = s.positions;
  // From round 2 on, a vertex checked in the last round can have been reached only by a face that
  // the last round's corrections moved, and only if one came near it: a bound per cell of the
  // grid (round 1 moves every contact of round 0: no bound to gain).
  const Real margin = kShiftMargin * std::max(A.thickness, B.thickness);
  const bool local = keepTracks_ && round_index_ >= 2 && shiftCells(a, b, x, margin);
  const Grid& grid = T.grid;
  for (uint32_t k = 0; k < T.vertices.size(); ++k) {
    // How far b's faces moved since the check: from the rebuild, or (checked in this stage) from
    // where the stage began: only the corrections of its rounds moved them since.
    Real faces = job.faceMoved + T.faceDrift[k];
    const Vec3& p = x[A.vertices[T.vertices[k]]];
    const bool checkedLast = T.checkedStage[k] == stage_ && T.checkedRound[k] + 1 == round_index_;
    const bool boundLast = T.roundStage[k] == stage_ && T.roundOf[k] + 1 == round_index_;
    if (local && (checkedLast || boundLast)) {
      // Checked (or found outside by this bound) in the last round: only the faces that round
      // moved, near it (shiftCells), can have reached it since.
      const Real c = checkedLast ? T.clearance[k] : T.roundClearance[k];
      const Vec3& at = checkedLast ? T.checkedAt[k] : T.roundAt[k];
      const bool in = !((p.array() < grid.box.lo.array()).any() || (p.array() > grid.box.hi.array()).any());
      const size_t cell =
          size_t((grid.cellOf(p.z(), 2) * grid.dims[1] + grid.cellOf(p.y(), 1)) * grid.dims[0] + grid.cellOf(p.x(), 0));
      const Real near = std::max(cellShift_[cell], in ? Real(0) : outsideShift_);
      const Real m = c - (p - at).norm() - near;
      if (m > 0) {  // outside, at least min(m, margin) from b's surface: for the next round's bound
        T.roundClearance[k] = std::min(m, margin), T.roundAt[k] = p;
        T.roundStage[k] = stage_, T.roundOf[k] = uint8_t(round_index_);
        continue;
      }
    }
    if (T.checkedStage[k] == stage_) faces = std::min(faces, job.faceCorrected + T.faceCorrected[k]);
    const Real m = T.clearance[k] - faces;
    if (keepTracks_ && m > 0 && (p - T.checkedAt[k]).squaredNorm() < m * m) continue;  // still outside
    looked_.push_back(k), lookedJob_.push_back(uint32_t(jobs_.size()));
  }
  if (local)
    for (uint32_t c : cellShiftSet_) cellShift_[c] = 0;
  job.end = uint32_t(looked_.size());
  jobs_.push_back(job);
  if (job.end == job.begin) return;
  T.grid.now.resize(T.grid.tri.size());  // the listed faces' boxes now (detectPairs): the queries prune by them
  for (size_t e = 0; e < T.grid.tri.size(); e += kBoxChunk)
    boxChunks_.push_back({uint32_t(jobs_.size() - 1), uint32_t(e)});
  if (T.nearest.size() != 2 * A.vertices.size()) T.nearest.assign(2 * A.vertices.size(), ContactBody::kNone);
}

}  // namespace gradel
