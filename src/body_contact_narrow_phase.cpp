// Narrow phase of the body-contact stage: each candidate vertex's nearest triangle of the other
// body within the search radius, inside when it lies behind the nearest feature's angle-weighted
// pseudo-normal (pseudo_normal.h); a round's lookups one batch on the thread team, gathered in
// pair then vertex order. Self-contact: a vertex that crossed a non-adjacent face of its own body.
// docs/speed.md, "Body contacts: the stage".
#include <algorithm>
#include <atomic>
#include <cmath>

#include "body_contact_grid.h"
#include "body_contact_tuning.h"
#include "gradel/body_contacts.h"
#include "pseudo_normal.h"
#include "thread_team.h"

namespace gradel {

// One detection pass into round_ over the pairs of bodies with pick[a * B + b] set (in index
// order; self-contact for a == b): the narrow phase of every pair as one batch, each vertex into
// its own slot (and its own entries of its track), gathered in pair then vertex order: the same
// contacts at any thread count. On the team's members for more than a few lookups (minParallel_;
// the world hands the stage its team only while the step's governor finds all members faster than
// one: on a busy machine waking the team costs more than this). active_: which pairs found one.
void BodyContacts::detectPairs(const BodyContactState& s, BodyContactStats& stats, const std::vector<uint8_t>& pick) {
  const size_t B = bodies_.size();
  jobs_.clear(), looked_.clear(), lookedJob_.clear(), boxChunks_.clear();
  for (size_t a = 0; a < B; ++a)
    for (size_t b = 0; b < B; ++b) {
      if (!pick[a * B + b]) continue;
      if (a == b)
        jobs_.push_back({uint32_t(a), uint32_t(a), 0, false, 0, 0, 0, 0});  // (self-contact: when gathered)
      else
        preparePair(a, b, s);
    }
  const uint32_t count = uint32_t(looked_.size());
  slot_.resize(count), slotState_.resize(count), slotTests_.resize(count);
  const Vec3* x = s.positions;
  auto one = [&](uint32_t j) {
    const PairJob& job = jobs_[lookedJob_[j]];
    Track& T = tracks_[job.a * B + job.b];
    const uint32_t k = looked_[j], i = T.vertices[k];
    slotState_[j] = uint8_t(detectVertex(bodies_[job.a], bodies_[job.b], T.grid, i, job.r, job.smallStep, x, &slot_[j],
                                         &T.clearance[k], &T.nearest[2 * size_t(i)], &slotTests_[j]));
    if (!keepTracks_) T.nearest[2 * size_t(i)] = T.nearest[2 * size_t(i) + 1] = ContactBody::kNone;  // (the reference)
    T.checkedAt[k] = x[bodies_[job.a].vertices[i]], T.faceDrift[k] = job.faceMoved;
    T.faceCorrected[k] = job.faceCorrected, T.checkedStage[k] = stage_, T.checkedRound[k] = uint8_t(round_index_);
  };
  // The pairs' faces' boxes now, in chunks of kBoxChunk, then the lookups.
  auto boxes = [&](uint32_t c) {
    const PairJob& job = jobs_[boxChunks_[c][0]];
    Grid& g = tracks_[job.a * B + job.b].grid;
    const ContactBody& F = bodies_[job.b];
    for (size_t e = boxChunks_[c][1]; e < std::min<size_t>(g.tri.size(), boxChunks_[c][1] + kBoxChunk); ++e) {
      const auto& u = F.triangles[g.tri[e]];
      g.now[e] = {x[u[0]].cwiseMin(x[u[1]]).cwiseMin(x[u[2]]), x[u[0]].cwiseMax(x[u[1]]).cwiseMax(x[u[2]])};
    }
  };
  const uint32_t boxChunks = uint32_t(boxChunks_.size());
  constexpr uint32_t kChunk = 16;
  if (team_ && team_->members() > 1 && count >= minParallel_) {
    std::atomic<uint32_t> nextBox{0}, next{0};
    team_->run([&](int) {
      for (uint32_t c; (c = nextBox.fetch_add(1, std::memory_order_relaxed)) < boxChunks;) boxes(c);
      team_->barrier();
      for (uint32_t j0; (j0 = next.fetch_add(kChunk, std::memory_order_relaxed)) < count;)
        for (uint32_t j = j0; j < std::min(count, j0 + kChunk); ++j) one(j);
    });
  } else {
    for (uint32_t c = 0; c < boxChunks; ++c) boxes(c);
    for (uint32_t j = 0; j < count; ++j) one(j);
  }
  stats.candidates += count;
  for (uint32_t j = 0; j < count; ++j) stats.faceTests += slotTests_[j];
  for (const PairJob& job : jobs_) {
    const size_t before = round_.size();
    if (job.a == job.b) {
      detectSelf(job.a, s, stats);
    } else {
      const std::vector<uint32_t>& candidates = tracks_[job.a * B + job.b].vertices;
      const ContactBody& A = bodies_[job.a];
      for (uint32_t j = job.begin; j < job.end; ++j) {
        stats.movedLookups += isTouched_[A.vertices[candidates[looked_[j]]]];
        if (slotState_[j] != 2) continue;
        round_.push_back(slot_[j]);
        stats.maxDepth = std::max(stats.maxDepth, slot_[j].depth);
      }
    }
    active_[job.a * B + job.b] = round_.size() > before;
  }
}

// Surface vertex i (index into A.vertices) against the faces of B in grid g (the pseudo-normal
// test, see the header). Reads the grid and positions only: any member may run any vertex.
int BodyContacts::detectVertex(const ContactBody& A, const ContactBody& B, const Grid& g, uint32_t i, Real r,
                               bool smallStep, const Vec3* x, Contact* out, Real* clearance, uint32_t* hint,
                               uint32_t* tests) const {
  const uint32_t v = A.vertices[i];
  const Vec3& p = x[v];
  const Nearest near = nearestTriangle(g, B, p, r, x, *hint);
  *hint = near.tri;
  *tests = near.tests;
  if (near.tri == ContactBody::kNone) {
    *clearance = r;  // no face of b within r (the track holds every face that can be)
    return 1;
  }
  const Real best = near.d2;
  const uint32_t bestTri = near.tri;
  const ClosestPoint bestCp = near.cp;
  const auto& tri = B.triangles[bestTri];
  const Vec3 c = bestCp.w[0] * x[tri[0]] + bestCp.w[1] * x[tri[1]] + bestCp.w[2] * x[tri[2]];
  const Real dist = std::sqrt(best);
  // The sign test. In front of (behind) every face around the nearest feature is in front of
  // (behind) their angle-weighted pseudo-normal: its weights are positive. Only a vertex in front
  // of some and behind others needs the weights (atan2 per corner).
  const int side = sideOfFaces(B, bestTri, bestCp.feature, p - c, x);
  Vec3 pn = Vec3::Zero();
  if (side == 0) pn = pseudoNormal(B, bestTri, bestCp.feature, x);
  if (side > 0 || (side == 0 && !((p - c).dot(pn) < 0))) {  // in front: outside, dist from b's surface
    *clearance = dist;
    return 1;
  }
  if (dist == 0 && side != 0) pn = pseudoNormal(B, bestTri, bestCp.feature, x);
  *clearance = -1;
  // The push: out of the nearest face that faces the vertex (its normal against the vertex's
  // own normal). Where two staircases interlock, the nearest face can be the riser of a step
  // that the vertex's body lies against on the same side (both normals along +x, say): pushing
  // each vertex out through such faces moves the two bodies into each other and never ends.
  Vec3 n = dist > 0 ? Vec3((c - p) / dist) : unit(pn);
  if (n.squaredNorm() == 0) return 1;
  OwnSide own(A, i, x);
  if (own.along(faceNormal(tri, x))) {
    // Only a face about as near (and within the search radius): a far one would move the vertex
    // far (and its face with it). The nearest one that faces the vertex with p behind its plane.
    const Real reach = std::min(r, dist + 0.5 * B.thickness);
    const Nearest f = nearestTriangle(g, B, p, reach, x, hint[1], [&](uint32_t t, const Vec3& cu) {
      const Vec3 fn = faceNormal(B.triangles[t], x);
      return fn.dot(p - cu) < 0 && !own.along(fn);
    });
    *tests += f.tests;
    const uint32_t facing = f.tri;
    const ClosestPoint facingCp = f.cp;
    if (facing != ContactBody::kNone) hint[1] = facing;
    if (facing != ContactBody::kNone) {
      const auto& u = B.triangles[facing];
      const Vec3 fn = unit(faceNormal(u, x));
      const Vec3 cu = facingCp.w[0] * x[u[0]] + facingCp.w[1] * x[u[1]] + facingCp.w[2] * x[u[2]];
      const Real depth = -fn.dot(p - cu);
      *out = {v, u, facingCp.w, fn, depth};
      return 2;
    }
  }
  if (side == 0 && smallStep) {
    // In front of some faces around the nearest edge or corner and behind others (a concave
    // one: outside is in front of them all). Along c - p the push would carry the vertex round
    // the feature to behind the faces it was in front of, and the next round would push it back
    // (two 64^3 balls pressed together: one vertex found at the same corner in all 8 rounds).
    // Out of the face it is deepest behind instead, at the feature's point on that face. (Only
    // in a small step: where a frame step crushed a ball, the faces around a feature can fold
    // back to back, and there this push left more vertices inside the other ball than the push
    // to the feature's point: two balls at 5 m/s each way, dt = 1/60 s.)
    Real deepest = 0;
    std::array<uint32_t, 3> face{};
    Vec3 faceN = Vec3::Zero();
    forFeatureFaces(B, bestTri, bestCp.feature, [&](const std::array<uint32_t, 3>& u) {
      const Vec3 fn = unit(faceNormal(u, x));
      const Real behind = -fn.dot(p - c);
      if (behind > deepest) deepest = behind, face = u, faceN = fn;
    });
    if (deepest > 0) {
      const ClosestPoint at = closestPointOnTriangle(c, x[face[0]], x[face[1]], x[face[2]]);
      *out = {v, face, at.w, faceN, deepest};
      return 2;
    }
  }
  *out = {v, tri, bestCp.w, n, dist};
  return 2;
}

// Surface vertices of body a against its own faces that are not adjacent (see the header).
void BodyContacts::detectSelf(size_t a, const BodyContactState& s, BodyContactStats& stats) {
  const ContactBody& A = bodies_[a];
  const Real r = A.thickness + 2 * moved_[a];
  Box box;
  for (uint32_t u : A.vertices) box.add(s.positions[u]);
  const Box region{box.lo - Vec3::Constant(r), box.hi + Vec3::Constant(r)};
  buildGrid(*grid_, A, region, s.positions, nullptr, r, 0);
  prepareScratch(*grid_);
  const Vec3 *x = s.positions, *x0 = s.previousPositions;
  for (uint32_t i = 0; i < A.vertices.size(); ++i) {
    const uint32_t v = A.vertices[i];
    const Vec3& p = x[v];
    const uint32_t* nearBegin = A.near.data() + A.nearStart[i];
    const uint32_t* nearEnd = A.near.data() + A.nearStart[i + 1];
    auto isNear = [&](uint32_t u) { return std::binary_search(nearBegin, nearEnd, u); };
    ++stats.candidates;
    Real bestS = -r;
    uint32_t bestTri = ContactBody::kNone;
    std::array<Real, 3> bestW{};
    Vec3 bestN;
    forCandidateTriangles(*grid_, p - Vec3::Constant(r), p + Vec3::Constant(r), scratch_[0], [&](uint32_t e) {
      const uint32_t t = grid_->tri[e];
      const auto& tri = A.triangles[t];
      const Vec3 f1 = faceNormal(tri, x);
      if (!(f1.dot(p - x[tri[0]]) < 0)) return;  // in front of the face's plane (most candidates)
      if (isNear(tri[0]) || isNear(tri[1]) || isNear(tri[2])) return;
      const Vec3 n1 = unit(f1);
      const Real s1 = n1.dot(p - x[tri[0]]);
      // Behind the face's plane now, the shallowest first (ties: the lowest id).
      if (!(s1 < 0 && (s1 > bestS || (s1 == bestS && bestTri != ContactBody::kNone && t < bestTri)))) return;
      const Real s0 = unit(faceNormal(tri, x0)).dot(x0[v] - x0[tri[0]]);
      if (!(s0 >= 0)) return;      // it was behind at the start already: it did not cross the face
      const Vec3 q = p - s1 * n1;  // its foot on the face's plane
      const ClosestPoint cp = closestPointOnTriangle(q, x[tri[0]], x[tri[1]], x[tri[2]]);
      const Vec3 c = cp.w[0] * x[tri[0]] + cp.w[1] * x[tri[1]] + cp.w[2] * x[tri[2]];
      if ((q - c).squaredNorm() > kSkin * kSkin * A.thickness * A.thickness) return;  // ends beside the face
      bestS = s1, bestTri = t, bestW = cp.w, bestN = n1;
    });
    if (bestTri == ContactBody::kNone) continue;
    round_.push_back({v, A.triangles[bestTri], bestW, bestN, -bestS});
    stats.maxDepth = std::max(stats.maxDepth, -bestS);
  }
}

// Every contact of the positions now, from scratch (the tracks rebuilt here, every candidate
// looked up), into round_: whether any vertex is inside another body (or, if on, crossed its own
// surface).
bool BodyContacts::detectAll(const BodyContactState& s, BodyContactStats& stats) {
  round_.clear();
  round_index_ = 0;
  tracksValid_ = false;
  measure(s);
  const size_t B = bodies_.size();
  if (B >= 2) rebuildTracks(s.positions), ++stats.rebuilds;
  pick_.assign(B * B, 1);
  for (size_t a = 0; a < B; ++a) pick_[a * B + a] = settings_.selfContact;
  detectPairs(s, stats, pick_);
  dropUnreachable(s, stats);
  return !round_.empty();
}

}  // namespace gradel
