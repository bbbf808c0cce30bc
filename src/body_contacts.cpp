#include "gradel/body_contacts.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <unordered_map>

#include "thread_team.h"

namespace gradel {

void validate(const BodyContactSettings& s) {
  if (!(s.restitution >= 0 && s.restitution <= 1))
    throw InputError("body_contact.restitution: expected a number in [0, 1], got " + std::to_string(s.restitution));
  if (!(s.friction >= 0 && std::isfinite(s.friction)))
    throw InputError("body_contact.friction: expected a finite number >= 0, got " + std::to_string(s.friction));
}

namespace {

// Compressed rows from per-row lists (each sorted and without repeats).
void toRows(std::vector<std::vector<uint32_t>>& lists, std::vector<uint32_t>& start, std::vector<uint32_t>& items) {
  start.assign(1, 0);
  items.clear();
  for (std::vector<uint32_t>& l : lists) {
    std::sort(l.begin(), l.end());
    l.erase(std::unique(l.begin(), l.end()), l.end());
    items.insert(items.end(), l.begin(), l.end());
    start.push_back(uint32_t(items.size()));
  }
}

}  // namespace

ContactBody buildContactBody(const DisplaySurface& surface, uint32_t vertexBegin, uint32_t vertexEnd, Real thickness,
                             const Vec3* rest, const uint8_t* onSurface, const ElementRows& elements) {
  if (surface.dim != 3) throw std::invalid_argument("buildContactBody: body contact needs a 3D body");
  if (!(thickness > 0)) throw std::invalid_argument("buildContactBody: thickness must be > 0");
  ContactBody b;
  b.vertexBegin = vertexBegin, b.vertexEnd = vertexEnd, b.thickness = thickness;
  auto world = [&](uint32_t s) {
    const uint64_t v = uint64_t(surface.modelVertex.at(s)) + vertexBegin;
    if (v >= vertexEnd) throw std::invalid_argument("buildContactBody: a surface corner lies outside the body");
    return uint32_t(v);
  };
  for (const auto& t : surface.triangles) b.triangles.push_back({world(t[0]), world(t[1]), world(t[2])});
  std::vector<uint8_t> corner(vertexEnd - vertexBegin, 0);
  for (const auto& t : b.triangles)
    for (uint32_t v : t) corner[v - vertexBegin] = 1;
  // Every vertex on the boundary (onSurface): the display surface's corners, and the vertices
  // inside its merged polygons (the middle of a coarse element's face), which move too.
  for (uint32_t i = 0; i < corner.size(); ++i)
    if (corner[i] || onSurface[i]) b.vertices.push_back(vertexBegin + i);
  b.indexOf.assign(vertexEnd - vertexBegin, ContactBody::kNone);
  for (uint32_t s = 0; s < b.vertices.size(); ++s) b.indexOf[b.vertices[s] - vertexBegin] = s;

  const size_t S = b.vertices.size();
  std::vector<std::vector<uint32_t>> tris(S), near(S);
  for (uint32_t t = 0; t < b.triangles.size(); ++t)
    for (uint32_t v : b.triangles[t]) {
      const uint32_t s = b.surfaceIndex(v);
      tris[s].push_back(t);
      near[s].insert(near[s].end(), b.triangles[t].begin(), b.triangles[t].end());  // the ring of faces
    }
  // A vertex inside a polygon takes the triangles that hold it at rest (for its normal and ring).
  std::unordered_map<uint64_t, uint32_t> inner;  // rest lattice point -> surface index
  auto key = [&](const Vec3& p) {
    const Vec3 q = (p - rest[0]) / thickness;
    auto c = [](Real v) { return uint64_t(int64_t(std::llround(v)) + (int64_t(1) << 20)) & 0x1fffff; };
    return c(q.x()) << 42 | c(q.y()) << 21 | c(q.z());
  };
  for (uint32_t s = 0; s < S; ++s)
    if (!corner[b.vertices[s] - vertexBegin]) inner.emplace(key(rest[b.vertices[s] - vertexBegin]), s);
  if (!inner.empty())
    for (uint32_t t = 0; t < b.triangles.size(); ++t) {
      const auto& tri = b.triangles[t];
      const Vec3 &p0 = rest[tri[0] - vertexBegin], &p1 = rest[tri[1] - vertexBegin], &p2 = rest[tri[2] - vertexBegin];
      const Vec3 lo = (p0.cwiseMin(p1).cwiseMin(p2) - rest[0]) / thickness;
      const Vec3 hi = (p0.cwiseMax(p1).cwiseMax(p2) - rest[0]) / thickness;
      for (long z = std::lround(lo.z()); z <= std::lround(hi.z()); ++z)
        for (long y = std::lround(lo.y()); y <= std::lround(hi.y()); ++y)
          for (long x = std::lround(lo.x()); x <= std::lround(hi.x()); ++x) {
            auto it = inner.find(key(rest[0] + thickness * Vec3(Real(x), Real(y), Real(z))));
            if (it == inner.end()) continue;
            const Vec3& p = rest[b.vertices[it->second] - vertexBegin];
            const ClosestPoint cp = closestPointOnTriangle(p, p0, p1, p2);
            if ((p - (cp.w[0] * p0 + cp.w[1] * p1 + cp.w[2] * p2)).norm() > 1e-9 * thickness) continue;
            tris[it->second].push_back(t);
            near[it->second].insert(near[it->second].end(), tri.begin(), tri.end());
          }
    }
  toRows(tris, b.vertexTriStart, b.vertexTris);
  // The vertices of every element at a surface vertex (self-contact adjacency).
  for (size_t e = elements.begin; e < elements.end; ++e) {
    const uint32_t p0 = elements.start[e], p1 = elements.start[e + 1];
    for (uint32_t p = p0; p < p1; ++p) {
      const uint32_t s = b.surfaceIndex(elements.verts[p] + elements.shift);
      if (s == ContactBody::kNone) continue;
      for (uint32_t q = p0; q < p1; ++q) near[s].push_back(elements.verts[q] + elements.shift);
    }
  }
  for (uint32_t s = 0; s < S; ++s) near[s].push_back(b.vertices[s]);
  toRows(near, b.nearStart, b.near);
  return b;
}

std::vector<ContactBody> buildContactBodies(const RestModel& world, const std::vector<const Layout*>& layouts,
                                            const std::vector<const VoxelVolume*>& volumes) {
  if (layouts.size() != world.bodies.size() || volumes.size() != world.bodies.size())
    throw std::invalid_argument("buildContactBodies: one layout and one volume per body");
  std::vector<ContactBody> out;
  for (size_t i = 0; i < world.bodies.size(); ++i) {
    const BodyRange& r = world.bodies[i];
    const DisplaySurface s = buildDisplaySurface(*layouts[i], *volumes[i], SurfaceKind::Voxel);
    out.push_back(buildContactBody(s, r.vertexBegin, r.vertexEnd, r.voxelSize,
                                   world.restPositions.data() + r.vertexBegin, world.onSurface.data() + r.vertexBegin,
                                   {world.elemStart.data(), world.elemVerts.data(), r.elementBegin, r.elementEnd, 0}));
  }
  return out;
}

ClosestPoint closestPointOnTriangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  // Voronoi regions of the corners, then the edges, then the face (the projection), each tested
  // with dot products of the edges against p's offsets from the corners.
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const Real d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return {{1, 0, 0}, 4};
  const Vec3 bp = p - b;
  const Real d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return {{0, 1, 0}, 5};
  const Real vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const Real v = d1 / (d1 - d3);
    return {{1 - v, v, 0}, 1};
  }
  const Vec3 cp = p - c;
  const Real d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return {{0, 0, 1}, 6};
  const Real vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const Real w = d2 / (d2 - d6);
    return {{1 - w, 0, w}, 3};
  }
  const Real va = d3 * d6 - d5 * d4;
  if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0) {
    const Real w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return {{0, 1 - w, w}, 2};
  }
  const Real sum = va + vb + vc;
  if (!(sum > 0)) return {{1, 0, 0}, 4};  // degenerate (flat) triangle: its first corner
  const Real v = vb / sum, w = vc / sum;
  return {{1 - v - w, v, w}, 0};
}

Real windingNumber(const Vec3& p, const std::vector<std::array<uint32_t, 3>>& triangles, const Vec3* x) {
  // Van Oosterom & Strackee's solid angle of each triangle seen from p.
  Real sum = 0;
  for (const auto& t : triangles) {
    const Vec3 a = x[t[0]] - p, b = x[t[1]] - p, c = x[t[2]] - p;
    const Real la = a.norm(), lb = b.norm(), lc = c.norm();
    const Real num = a.dot(b.cross(c));
    const Real den = la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb;
    sum += 2 * std::atan2(num, den);
  }
  return sum / (4 * M_PI);
}

namespace {

Vec3 faceNormal(const std::array<uint32_t, 3>& t, const Vec3* x) {
  return (x[t[1]] - x[t[0]]).cross(x[t[2]] - x[t[0]]);
}

Vec3 unit(const Vec3& v) {
  const Real n = v.norm();
  return n > 0 ? Vec3(v / n) : Vec3::Zero();
}

// The angle-weighted pseudo-normal (not normalised) at surface vertex s of the body.
Vec3 vertexPseudoNormal(const ContactBody& body, uint32_t s, const Vec3* x) {
  const uint32_t a = body.vertices[s];
  Vec3 n = Vec3::Zero();
  for (uint32_t k = body.vertexTriStart[s]; k < body.vertexTriStart[s + 1]; ++k) {
    const auto& u = body.triangles[body.vertexTris[k]];
    const int i = u[0] == a ? 0 : (u[1] == a ? 1 : (u[2] == a ? 2 : -1));
    if (i < 0) {  // a vertex inside the face (buildContactBody)
      n += unit(faceNormal(u, x));
      continue;
    }
    const Vec3 e1 = x[u[size_t((i + 1) % 3)]] - x[a], e2 = x[u[size_t((i + 2) % 3)]] - x[a];
    const Real angle = std::atan2(e1.cross(e2).norm(), e1.dot(e2));
    n += angle * unit(faceNormal(u, x));
  }
  return n;
}

// Which way a surface vertex's body lies, asked of several directions f: whether f . n >= 0 for
// its angle-weighted pseudo-normal n. The weights are positive, so where f is on one side of every
// face around the vertex the answer needs no angle (atan2 per face); only mixed sides (or a flat
// face) compute n, once.
class OwnSide {
 public:
  OwnSide(const ContactBody& body, uint32_t s, const Vec3* x) : body_(body), s_(s), x_(x) {
    const uint32_t k0 = body.vertexTriStart[s], k1 = body.vertexTriStart[s + 1];
    count_ = k1 - k0 <= kMax ? int(k1 - k0) : -1;  // (more faces than kept: always n)
    for (int k = 0; k < count_; ++k)
      normals_[size_t(k)] = faceNormal(body.triangles[body.vertexTris[k0 + uint32_t(k)]], x);
  }
  bool along(const Vec3& f) {
    int along = 0, against = 0;
    for (int k = 0; k < count_; ++k) {
      const Real d = normals_[size_t(k)].dot(f);
      along += d > 0, against += d < 0;
    }
    if (count_ > 0 && against == count_) return false;
    if (count_ > 0 && along == count_) return true;
    if (!haveN_) n_ = vertexPseudoNormal(body_, s_, x_), haveN_ = true;
    return f.dot(n_) >= 0;
  }

 private:
  static constexpr uint32_t kMax = 24;
  const ContactBody& body_;
  uint32_t s_;
  const Vec3* x_;
  std::array<Vec3, kMax> normals_;
  int count_ = 0;
  bool haveN_ = false;
  Vec3 n_;
};

// The angle-weighted pseudo-normal (not normalised) of the feature of triangle t that the closest
// point lies on (closestPointOnTriangle's feature), from the body's faces around it.
// f(u) for each face around the feature of triangle t that a closest point lies on
// (closestPointOnTriangle's): the face itself; an edge's faces, those holding both of its ends; a
// corner's faces (with those that hold it inside, buildContactBody), in the body's order.
template <class F>
void forFeatureFaces(const ContactBody& body, uint32_t t, int feature, F&& f) {
  const auto& tri = body.triangles[t];
  if (feature == 0) return f(tri);
  const uint32_t a = tri[size_t(feature <= 3 ? feature - 1 : feature - 4)];
  const uint32_t s = body.surfaceIndex(a);
  for (uint32_t k = body.vertexTriStart[s]; k < body.vertexTriStart[s + 1]; ++k) {
    const auto& u = body.triangles[body.vertexTris[k]];
    if (feature <= 3) {  // an edge
      const uint32_t b = tri[size_t(feature % 3)];
      if (u[0] != b && u[1] != b && u[2] != b) continue;
    }
    f(u);
  }
}

Vec3 pseudoNormal(const ContactBody& body, uint32_t t, int feature, const Vec3* x) {
  if (feature == 0) return unit(faceNormal(body.triangles[t], x));
  if (feature <= 3) {  // an edge: the unit normals of its faces
    Vec3 n = Vec3::Zero();
    forFeatureFaces(body, t, feature, [&](const std::array<uint32_t, 3>& u) { n += unit(faceNormal(u, x)); });
    return n;
  }
  return vertexPseudoNormal(body, body.surfaceIndex(body.triangles[t][size_t(feature - 4)]), x);
}

// Which side of the faces around a closest point's feature the offset d = p - c lies on: 1 in
// front of every one (strictly), -1 behind every one, 0 mixed or on one.
int sideOfFaces(const ContactBody& body, uint32_t t, int feature, const Vec3& d, const Vec3* x) {
  int front = 0, behind = 0, faces = 0;
  forFeatureFaces(body, t, feature, [&](const std::array<uint32_t, 3>& u) {
    const Real s = faceNormal(u, x).dot(d);
    ++faces, front += s > 0, behind += s < 0;
  });
  return faces > 0 && front == faces ? 1 : (faces > 0 && behind == faces ? -1 : 0);
}

// Generalised inverse mass of a contact: vertex plus the face's point with weights w.
Real contactInvMass(const BodyContacts::Contact& c, const Real* im) {
  return im[c.vertex] + c.w[0] * c.w[0] * im[c.face[0]] + c.w[1] * c.w[1] * im[c.face[1]] +
         c.w[2] * c.w[2] * im[c.face[2]];
}

// Applies the impulse-like change j along a direction d (per unit generalised mass): the vertex
// moves by im_p j d, the face's corners by -w_k im_k j d. Used for positions and velocities.
void applyPair(const BodyContacts::Contact& c, const Real* im, Vec3* y, const Vec3& jd) {
  y[c.vertex] += im[c.vertex] * jd;
  for (int k = 0; k < 3; ++k) y[c.face[size_t(k)]] -= c.w[size_t(k)] * im[c.face[size_t(k)]] * jd;
}

Vec3 relative(const BodyContacts::Contact& c, const Vec3* y) {
  return y[c.vertex] - (c.w[0] * y[c.face[0]] + c.w[1] * y[c.face[1]] + c.w[2] * y[c.face[2]]);
}

constexpr Real kSkin = 1e-6;  // [thickness] a corrected vertex ends this far outside
// [thickness] a step in which two surfaces together moved at most this far (before the
// corrections) is small (detectVertex).
constexpr Real kSmallStep = 0.25;

// A triangle whose box lies farther than this times the best squared distance so far (plus a
// tiny absolute slack) cannot be nearer than the best, nor as near: the slack covers rounding.
constexpr Real kPrune = 1 + 1e-9;

// The tracks (header, "across steps"): a surface may move this far (times the larger voxel size
// of the bodies) from where it was at the rebuild, and a step's search radius may grow this much
// (same unit) over the radius at the rebuild, before every track is rebuilt. Measured on two 64^3
// spheres in contact (gradel-bench --sets contact): see docs/speed.md.
constexpr Real kLoose = 0.5, kRadiusSlack = 0.25;
// A track's grid: cells of twice this (same unit); the queries start from their last answer, so
// their boxes are small and fine cells hold few faces.
constexpr Real kTrackCell = 0.5;
// measure(): surface vertices per chunk (a unit of the team's work).
constexpr uint32_t kMeasureChunk = 4096;
// detectPairs(): faces per chunk of the boxes now (a unit of the team's work).
constexpr uint32_t kBoxChunk = 512;
// shiftCells(): a vertex a round's local bound skips keeps at most this clearance (same unit).
constexpr Real kShiftMargin = 0.125;

// Squared distance from p to a box (0 inside): a lower bound of the distance to what it holds.
Real boxDistance2(const Vec3& lo, const Vec3& hi, const Vec3& p) {
  return (lo - p).cwiseMax(p - hi).cwiseMax(Vec3::Zero()).squaredNorm();
}

}  // namespace

BodyContacts::BodyContacts(std::vector<ContactBody> bodies, const BodyContactSettings& settings)
    : bodies_(std::move(bodies)), settings_(settings) {
  validate(settings_);
  Real thinnest = std::numeric_limits<Real>::infinity(), thickest = 0;
  for (const ContactBody& b : bodies_)
    thinnest = std::min(thinnest, b.thickness), thickest = std::max(thickest, b.thickness);
  skin_ = kSkin * thinnest;
  loose_ = kLoose * thickest;
  const size_t B = bodies_.size();
  bounds_.resize(B);
  active_.assign(B * B, 0);
  tracks_.resize(B * B);
  moved_.assign(B, 0), movedStart_.assign(B, 0), sinceRebuild_.assign(B, 0), sinceRebuildStart_.assign(B, 0);
  sinceAxis_.assign(B, 0), sinceAxisStart_.assign(B, 0);
  uint32_t vertexEnd = 0;
  blockStart_.assign(1, 0), chunkStart_.assign(1, 0);
  for (size_t b = 0; b < B; ++b) {
    vertexEnd = std::max(vertexEnd, bodies_[b].vertexEnd);
    blockStart_.push_back(blockStart_.back() +
                          uint32_t((bodies_[b].vertices.size() + kBoundsBlock - 1) / kBoundsBlock));
    chunkStart_.push_back(
        chunkStart_.back() +
        uint32_t((bodies_[b].vertexEnd - bodies_[b].vertexBegin + kMeasureChunk - 1) / kMeasureChunk));
  }
  chunkMotion_.resize(chunkStart_.back());  // (every chunk writes its own)
  blockBox_.resize(blockStart_.back());
  isTouched_.assign(vertexEnd, 0);
  roundShift_.assign(vertexEnd, 0);
  roundShiftMax_.assign(B, 0);
  ref_.assign(vertexEnd, RefPoint{0, 0, 0, 0});
  refRounding_.assign(B, Vec3::Zero());
  bodyOf_.assign(vertexEnd, uint32_t(B));
  for (size_t b = 0; b < B; ++b)
    for (uint32_t u : bodies_[b].vertices) bodyOf_[u] = uint32_t(b);
}

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
  if (team_ && team_->members() > 1 && chunks >= 4) {
    std::atomic<uint32_t> next{0};
    team_->run([&](int) {
      for (uint32_t c; (c = next.fetch_add(1, std::memory_order_relaxed)) < chunks;) one(c);
    });
  } else {
    for (uint32_t c = 0; c < chunks; ++c) one(c);
  }
  for (size_t b = 0; b < B; ++b) {
    BodyMotion m;
    for (uint32_t c = chunkStart_[b]; c < chunkStart_[b + 1]; ++c) m.add(chunkMotion_[c]);
    setMotion(b, m);
  }
}

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

// A contact's vertices may move from now on (the only ones a correction moves): remember where
// they were when the stage began (no correction has moved them yet).
void BodyContacts::markTouched(const Contact& c, const Vec3* x) {
  auto mark = [&](uint32_t u) {
    if (isTouched_[u]) return;
    isTouched_[u] = 1;
    touched_.push_back(u);
    touchedStart_.push_back(x[u]);
    touchedLast_.push_back(x[u]);
  };
  mark(c.vertex);
  for (uint32_t u : c.face) mark(u);
}

inline int64_t BodyContacts::Grid::cellOf(Real v, int a) const {
  return int64_t(std::clamp(std::floor((v - origin[a]) * inv), Real(0), Real(dims[size_t(a)] - 1)));
}

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

// The cell ranges of the query box [lo, hi] per axis; false when it misses every listed face.
bool BodyContacts::Grid::rangeOf(const Vec3& lo, const Vec3& hi, std::array<int64_t, 6>& c) const {
  if (count == 0 || (hi.array() < box.lo.array()).any() || (lo.array() > box.hi.array()).any()) return false;
  for (int a = 0; a < 3; ++a) c[size_t(a)] = cellOf(lo[a], a), c[size_t(a + 3)] = cellOf(hi[a], a);
  return true;
}

// The dedupe stamps of every member, sized for grid g's faces.
void BodyContacts::prepareScratch(const Grid& g) {
  const size_t members = team_ ? size_t(team_->members()) : 1;
  if (scratch_.size() < members) scratch_.resize(members);
  for (QueryScratch& q : scratch_)
    if (q.seen.size() < g.tri.size()) q.seen.assign(g.tri.size(), q.stamp);
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

BodyContacts::Nearest BodyContacts::nearestTriangle(const Grid& g, const ContactBody& faces, const Vec3& p, Real reach,
                                                    const Vec3* x, uint32_t hint) const {
  return nearestTriangle(g, faces, p, reach, x, hint, [](uint32_t, const Vec3&) { return true; });
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
  slot_.resize(count), slotState_.resize(count);
  const Vec3* x = s.positions;
  auto one = [&](uint32_t j) {
    const PairJob& job = jobs_[lookedJob_[j]];
    Track& T = tracks_[job.a * B + job.b];
    const uint32_t k = looked_[j], i = T.vertices[k];
    slotState_[j] = uint8_t(detectVertex(bodies_[job.a], bodies_[job.b], T.grid, i, job.r, job.smallStep, x, &slot_[j],
                                         &T.clearance[k], &T.nearest[2 * size_t(i)]));
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
                               bool smallStep, const Vec3* x, Contact* out, Real* clearance, uint32_t* hint) const {
  const uint32_t v = A.vertices[i];
  const Vec3& p = x[v];
  const Nearest near = nearestTriangle(g, B, p, r, x, *hint);
  *hint = near.tri;
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
  buildGrid(grid_, A, region, s.positions, nullptr, r, 0);
  prepareScratch(grid_);
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
    forCandidateTriangles(grid_, p - Vec3::Constant(r), p + Vec3::Constant(r), scratch_[0], [&](uint32_t e) {
      const uint32_t t = grid_.tri[e];
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

// The pseudo-normal test reads "inside" off the faces around the nearest feature, which is only
// right where the surface near it is not folded. A soft body crushed by a stiffer one folds its
// surface (elements at a third of their volume), and there a vertex that never came near was read
// inside by up to a voxel: pushed out along a far face, it set the bodies ringing (a stiff 9^3 ball
// at 1.45 m/s into a soft 6^3 one: energy x1.8 in one step, then x28 once the last resort took the
// bodies back over such "contacts"). A contact deeper than the vertex and the other body's surface
// can have come towards each other in the step (plus what a step may leave: kTakeBackDepth) cannot
// be from a vertex that was outside at the step's start; such a one is asked of the winding number
// of the other body's closed surface (exact, O(faces), rare) and dropped when that says outside.
// Explicit steps only (s.leapfrog: a step moves a surface a fraction of a voxel): where a frame-size
// step crushed a ball to half its size within the step, its surface folds through itself and the
// winding number is no better a judge than the pseudo-normal (two balls at 10 m/s each, dt = 1/60 s:
// dropping such findings left one more step with a vertex inside).
void BodyContacts::dropUnreachable(const BodyContactState& s, BodyContactStats& stats) {
  const Vec3* x0 = s.previousPositions;
  if (!x0 || !s.leapfrog) return;
  const Vec3* x = s.positions;
  size_t kept = 0;
  for (size_t k = 0; k < round_.size(); ++k) {
    const Contact& c = round_[k];
    const uint32_t b = bodyOf_[c.face[0]];
    const Real reach = (x[c.vertex] - x0[c.vertex]).norm() + moved_[b] + kTakeBackDepth * bodies_[b].thickness + skin_;
    if (!(c.depth > reach) || !(std::abs(windingNumber(x[c.vertex], bodies_[b].triangles, x)) < 0.5)) {
      round_[kept++] = c;
    } else {
      ++stats.unreachable;
    }
  }
  round_.resize(kept);
}

// The last resort (header): while a vertex is inside deeper than kTakeBackDepth of a voxel, the
// bodies of the contacts go back along the straight line from where they ended towards where they
// started, all by one fraction, positions and velocities alike (the taken-back bodies make that
// fraction of the step; keeping the step's velocities while taking the positions back let the
// elastic forces of a pressed pair accelerate the bodies step after step without moving them: two
// balls at 4 m/s, energy x1e5). Shallower leftovers are pushed out once more and kept as contacts.
void BodyContacts::takeBack(const BodyContactState& s, BodyContactStats& stats) {
  if (!detectAll(s, stats)) return;
  Vec3* x = s.positions;
  Vec3* v = s.velocities;
  const Vec3* x0 = s.previousPositions;
  const Vec3* v0 = s.previousVelocities;
  const Real* im = s.invMass;
  const size_t B = bodies_.size();
  // Deeper than the tolerance, for the contacts of round_ now; beyond: deeper than the tolerance
  // beyond where the vertex lay behind the same point of the face (along the same normal) at the
  // step's start.
  auto deep = [&](bool beyond) {
    for (const Contact& c : round_) {
      const Real atStart = beyond ? std::max(Real(0), -c.n.dot(relative(c, x0))) : Real(0);
      if (c.depth > kTakeBackDepth * bodies_[bodyOf_[c.face[0]]].thickness + atStart) return true;
    }
    return false;
  };
  std::vector<uint8_t> back(B, 0);
  std::vector<std::vector<Vec3>> end(B), endV(B);  // a body's positions and velocities when it joined
  Real f = 1;
  while (deep(false)) {
    // At the least fraction, deep only where the vertices were already about as deep at the
    // step's start: taking the step back cannot undo that (where elements inverted, the sign test
    // read a vertex outside at the start and 0.44 voxel inside after 1/16 of the step: it had moved
    // 0.014 voxel, and the winding number said inside at both). Taken back to that start in every
    // step, the pair never moved again (two 16^3 balls at 10 m/s, generic build: 2,234 of 2,424
    // steps taken back): the bodies keep this fraction of the step instead.
    if (f == kTakeBackLeast && !deep(true)) break;
    bool grew = false;
    for (const Contact& c : round_)
      for (const size_t b : {size_t(bodyOf_[c.vertex]), size_t(bodyOf_[c.face[0]])})  // (both on a surface)
        if (b < B && !back[b]) {
          back[b] = 1, grew = true;
          end[b].assign(x + bodies_[b].vertexBegin, x + bodies_[b].vertexEnd);
          endV[b].assign(v + bodies_[b].vertexBegin, v + bodies_[b].vertexEnd);
        }
    if (f == 0 && !grew) break;  // nothing left to take back (pinned vertices stay)
    f = f > kTakeBackLeast ? f / 2 : 0;
    for (size_t b = 0; b < B; ++b) {
      if (!back[b]) continue;
      const uint32_t begin = bodies_[b].vertexBegin;
      for (uint32_t u = begin; u < bodies_[b].vertexEnd; ++u) {
        if (im[u] == 0) continue;
        x[u] = x0[u] + f * (end[b][u - begin] - x0[u]);
        if (v0) v[u] = v0[u] + f * (endV[b][u - begin] - v0[u]);
      }
    }
    ++stats.takeBacks;
    if (!detectAll(s, stats)) break;
  }
  stats.takenBackTo = f;
  if (round_.empty()) return;
  // What is left is shallow (or could not be taken back: pinned): out once more, as a round's contacts.
  contacts_.insert(contacts_.end(), round_.begin(), round_.end());
  for (int it = 0; it < kIterations; ++it)
    for (const Contact& c : round_) {
      const Real W = contactInvMass(c, im);
      const Real gap = c.n.dot(relative(c, x)) - skin_;
      if (W > 0 && gap < 0) applyPair(c, im, x, (-gap / W) * c.n);
    }
}

// The warm start (header): the last stage's contacts whose vertex and face corners start this
// step where that stage left them, in a small step of their pair (a face that moved less than a
// quarter voxel is still the surface there), are round 0's contacts where the vertex now lies
// behind the contact's plane as it was found (its normal, its point at weights w on the face now).
// The detection rounds then check every candidate as ever. Measured (two 64^3 balls pressed, 400
// steps, every contact kept): the plane as found beats the face's plane now (545 lookups a step
// against 745) and one contact per vertex (724): a vertex carried against two faces stays out of both.
bool BodyContacts::applyWarm(const BodyContactState& s, BodyContactStats& stats) {
  if (!warmStart_ || warm_.empty()) return false;
  const Vec3* x = s.positions;
  const Vec3* x0 = s.previousPositions;
  for (size_t k = 0; k < warm_.size(); ++k) {
    const Contact& c = warm_[k];
    const Vec3* at = &warmAt_[4 * k];
    if (x0[c.vertex] != at[0] || x0[c.face[0]] != at[1] || x0[c.face[1]] != at[2] || x0[c.face[2]] != at[3])
      continue;  // moved since (walls, or a state set from outside)
    const uint32_t a = bodyOf_[c.vertex], b = bodyOf_[c.face[0]];
    if (!(movedStart_[a] + movedStart_[b] <= kSmallStep * std::max(bodies_[a].thickness, bodies_[b].thickness)))
      continue;
    const Real gap = c.n.dot(relative(c, x));
    if (!(gap < 0)) continue;
    round_.push_back(c);
    round_.back().depth = -gap;
  }
  warm_.clear(), warmAt_.clear();
  stats.warm = round_.size();
  return !round_.empty();
}

// What the next stage's warm start reads: this stage's body-body contacts (after the last resort
// too: dropping them there left a generic build's pressed balls in it for many steps), one per vertex and face, the
// first in the stage's order (a contact carried over from the last stage comes first: its plane as first found, kept
// while the vertex is behind it), and where its vertex and face corners end the stage. Measured (two 64^3 balls
// pressed, 1,500 steps, the whole collision): all of them, a vertex-face pair found again each step adding one, grew to
// 6,000 contacts a step for 1,300 vertices (2,191 a step on average against 516), for the same lookups and no faster;
// the last one found per pair is not behind its plane in the next step (its bounce moves it away), which leaves no warm
// start (891 lookups a step at 400 steps, against 971 without one).
void BodyContacts::keepWarm(const Vec3* x) {
  warm_.clear(), warmAt_.clear();
  if (!warmStart_) return;
  warmKeys_.clear();
  for (uint32_t k = 0; k < contacts_.size(); ++k) {
    const Contact& c = contacts_[k];
    if (bodyOf_[c.vertex] != bodyOf_[c.face[0]])  // (self-contact: found by its own rule)
      warmKeys_.push_back({{c.vertex, c.face[0], c.face[1], c.face[2]}, k});
  }
  std::stable_sort(warmKeys_.begin(), warmKeys_.end(), [](const auto& l, const auto& r) { return l.first < r.first; });
  warmKeys_.erase(
      std::unique(warmKeys_.begin(), warmKeys_.end(), [](const auto& l, const auto& r) { return l.first == r.first; }),
      warmKeys_.end());  // (the first of each run of equal keys stays)
  std::sort(warmKeys_.begin(), warmKeys_.end(), [](const auto& l, const auto& r) { return l.second < r.second; });
  for (const auto& key : warmKeys_) {
    const Contact& c = contacts_[key.second];
    warm_.push_back(c);
    warmAt_.insert(warmAt_.end(), {x[c.vertex], x[c.face[0]], x[c.face[1]], x[c.face[2]]});
  }
}

BodyContactStats BodyContacts::resolve(const BodyContactState& s) {
  const auto t0 = std::chrono::steady_clock::now();
  BodyContactStats stats;
  contacts_.clear();
  if (empty()) return stats;
  Vec3* x = s.positions;
  Vec3* v = s.velocities;
  const Real* im = s.invMass;
  for (uint32_t u : touched_) isTouched_[u] = 0, roundShift_[u] = 0;
  touched_.clear(), touchedStart_.clear(), touchedLast_.clear();
  ++stage_;
  bool fellBack = false;
  const size_t B = bodies_.size();
  int firstDetect = 0;  // the first detection round: 1 after a warm start (round 0 applied the last stage's contacts)
  for (int round = 0; round < kRounds + firstDetect; ++round) {
    // Broad phase: how far each body's surface moved in the step and since the tracks' rebuild
    // (round 0: one pass over the surfaces; a later round adds what the corrections moved since).
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
    if (B >= 2 && (!keepTracks_ || !tracksHold())) {
      rebuildTracks(x), ++stats.rebuilds;  // (sinceRebuild_ 0: a later round adds the corrections to come)
    }
    // After the first round only the pairs with a body that a correction of the round before
    // moved: a contact of a's vertices against b's faces moves vertices of both, so it can push
    // a vertex of b into a face of a (pair (b, a)) or into a third body's faces as well.
    round_.clear();
    round_index_ = round;
    if (round == 0 && applyWarm(s, stats)) {
      firstDetect = 1;  // the warm contacts are this round's: pushed out below, then every pair is detected
    } else {
      movedBodies_.assign(B, 0);
      for (size_t a = 0; a < B; ++a)
        for (size_t b = 0; b < B; ++b)
          if (active_[a * B + b]) movedBodies_[a] = movedBodies_[b] = 1;
      pick_.assign(B * B, 0);
      for (size_t a = 0; a < B; ++a)
        for (size_t b = 0; b < B; ++b) {
          if (a == b && !settings_.selfContact) continue;
          if (round > firstDetect && !movedBodies_[a] && !movedBodies_[b]) {
            active_[a * B + b] = 0;
            continue;
          }
          pick_[a * B + b] = 1;
        }
      detectPairs(s, stats, pick_);
      dropUnreachable(s, stats);
      stats.rounds = round + 1 - firstDetect;
      if (round_.empty()) break;
      if (round + 1 == kRounds + firstDetect) {
        fellBack = true;
        // Still inside after every round: contacts that contradict each other (two vertices each
        // inside the other body behind faces they are corners of, where coarse staircases cross).
        // Each such vertex and its face point go back to where they were relative to each other at
        // the start of the step, when the vertex was outside (split by inverse mass, as above).
        for (int it = 0; it < kIterations; ++it)
          for (const Contact& c : round_) {
            const Real W = contactInvMass(c, im);
            if (W > 0) applyPair(c, im, x, (relative(c, s.previousPositions) - relative(c, x)) / W);
          }
        contacts_.insert(contacts_.end(), round_.begin(), round_.end());
        break;
      }
    }
    // Positions, Gauss-Seidel over every contact found so far (a later round's contacts and an
    // earlier round's act together): out to the skin along n, split by inverse mass; friction
    // undoes the tangential slip of the step up to friction x depth (once, when first found).
    const size_t first = contacts_.size();
    contacts_.insert(contacts_.end(), round_.begin(), round_.end());
    for (const Contact& c : round_) markTouched(c, x);
    // kIterations sweeps, then more (up to kMaxIterations) while a sweep still found a vertex
    // behind its contact point along the normal (gap < -skin: n . (p - c) < 0): where contacts
    // share vertices (a corner pushed by the vertices around it) each sweep undoes part of the
    // one before, and what a round leaves the next finds again (two 64^3 balls pressed together,
    // 400 steps: 1,413 lookups a step against 1,555 with 4 sweeps; docs/speed.md).
    for (int it = 0; it < kMaxIterations; ++it) {
      bool inside = false;
      for (size_t k = 0; k < contacts_.size(); ++k) {
        const Contact& c = contacts_[k];
        const Real W = contactInvMass(c, im);
        if (!(W > 0)) continue;
        const Real gap = c.n.dot(relative(c, x)) - skin_;
        if (gap >= 0) continue;
        inside = inside || gap < -skin_;
        applyPair(c, im, x, (-gap / W) * c.n);
        if (it == 0 && k >= first && settings_.friction > 0) {
          Vec3 slip = relative(c, x) - relative(c, s.previousPositions);
          slip -= slip.dot(c.n) * c.n;
          const Real len = slip.norm(), allowed = settings_.friction * -gap;
          if (len > 0) applyPair(c, im, x, (-(len <= allowed ? Real(1) : allowed / len) / W) * slip);
        }
      }
      if (it + 1 >= kIterations && !inside) break;
    }
  }
  if (fellBack) takeBack(s, stats);
  keepWarm(x);
  // Velocities: equal and opposite impulses on the relative velocity at each contact, never adding
  // kinetic energy (the manipulators' rules, contacts.h). With symplectic Euler the stored velocity
  // is half a step behind the positions: the relative velocity at their time is w = rel + a dt / 2,
  // a dt the step's change of the contact's relative velocity (from the velocities the response
  // started with: entry_); the impulses act on w. An impulse that takes the normal part of w from
  // wn < 0 to wn' with |wn'| <= |wn| and shrinks the tangential part changes the kinetic energy by
  // (|w'|^2 - |w|^2) / (2 W) <= 0, whatever the other contacts on the same vertices did before it.
  const Real e = settings_.restitution, mu = settings_.friction;
  const Vec3* v0 = s.previousVelocities;
  const bool leap = s.leapfrog && v0;
  const bool timed = v0 && s.dt > 0;
  entry_.resize(contacts_.size());
  for (size_t k = 0; k < contacts_.size(); ++k) entry_[k] = relative(contacts_[k], v);
  for (size_t k = 0; k < contacts_.size(); ++k) {
    const Contact& c = contacts_[k];
    const Real W = contactInvMass(c, im);
    if (!(W > 0)) continue;
    const Vec3 start = v0 ? relative(c, v0) : entry_[k];
    const Vec3 half = leap ? Vec3(0.5 * (entry_[k] - start)) : Vec3::Zero();  // a dt / 2
    const Vec3 w = relative(c, v) + half;
    const Real wn = w.dot(c.n);
    if (!(wn < 0)) continue;  // receding at the time of the positions: its next step takes it out
    // The bounce: restitution times the speed at which the contact approached at the start of the
    // step, never more than it has now; nothing for one that was resting or receding then (rule 1).
    const Real u0 = start.dot(c.n);
    Real out = u0 < 0 ? e * std::min(-u0, -wn) : Real(0);
    // The elastic energy the position projection stored (rule 2): pushed apart by `depth` along n
    // against the relative acceleration an < 0 that pressed the vertex in, -an depth per unit of
    // generalised mass 1 / W; taken out of the bounce, then out of the sliding.
    Real stored = timed ? std::max(Real(0), -(entry_[k] - start).dot(c.n) / s.dt) * c.depth : Real(0);
    const Real fromBounce = std::min(stored, Real(0.5) * out * out);
    out = std::sqrt(std::max(Real(0), out * out - 2 * fromBounce));
    stored -= fromBounce;
    const Real jn = (out - wn) / W;
    Vec3 wt = w - wn * c.n;
    const Real wtLen = wt.norm();
    Vec3 dv = (out - wn) * c.n;  // the change of the relative velocity
    if (wtLen > 0 && (mu > 0 || stored > 0)) {
      // Coulomb: the tangential impulse at most mu times the normal one; then the stored energy.
      Real keep = std::max(Real(0), wtLen - mu * jn * W);
      if (stored > 0) keep = std::sqrt(std::max(Real(0), keep * keep - 2 * stored));
      dv += ((keep - wtLen) / wtLen) * wt;
    }
    applyPair(c, im, v, dv / W);
  }
  stats.contacts = contacts_.size();
  stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return stats;
}

}  // namespace gradel

namespace gradel {

// Frame-size integrators (header): the broad phase of a step and the proximity list.
bool BodyContacts::mayTouch(const Vec3* x, const Vec3* xEnd, Real margin) const {
  std::vector<Box> box(bodies_.size());
  for (size_t b = 0; b < bodies_.size(); ++b)
    for (uint32_t u : bodies_[b].vertices) box[b].add(x[u]), box[b].add(xEnd[u]);
  for (size_t a = 0; a < box.size(); ++a)
    for (size_t b = a + 1; b < box.size(); ++b)
      if (((box[a].lo.array() - margin) <= box[b].hi.array()).all() &&
          ((box[b].lo.array() - margin) <= box[a].hi.array()).all())
        return true;
  return false;
}

void BodyContacts::proximity(const Vec3* x, Real margin, std::vector<Proximity>& out) {
  out.clear();
  const size_t B = bodies_.size();
  std::vector<Box> box(B);
  for (size_t b = 0; b < B; ++b)
    for (uint32_t u : bodies_[b].vertices) box[b].add(x[u]);
  for (size_t a = 0; a < B; ++a)
    for (size_t b = 0; b < B; ++b) {
      if (a == b) continue;
      const ContactBody& A = bodies_[a];
      const ContactBody& F = bodies_[b];
      const Box q{box[a].lo.cwiseMax(box[b].lo - Vec3::Constant(margin)),
                  box[a].hi.cwiseMin(box[b].hi + Vec3::Constant(margin))};
      if ((q.lo.array() > q.hi.array()).any()) continue;
      buildGrid(grid_, F, {q.lo - Vec3::Constant(margin), q.hi + Vec3::Constant(margin)}, x, nullptr, margin, 0);
      if (grid_.count == 0) continue;
      for (uint32_t v : A.vertices) {
        const Vec3& p = x[v];
        if ((p.array() < q.lo.array()).any() || (p.array() > q.hi.array()).any()) continue;
        const Nearest near = nearestTriangle(grid_, F, p, margin, x);
        if (near.tri == ContactBody::kNone) continue;
        const Real best = near.d2;
        const uint32_t bestTri = near.tri;
        const ClosestPoint bestCp = near.cp;
        const auto& tri = F.triangles[bestTri];
        const Vec3 c = bestCp.w[0] * x[tri[0]] + bestCp.w[1] * x[tri[1]] + bestCp.w[2] * x[tri[2]];
        const Vec3 pn = unit(pseudoNormal(F, bestTri, bestCp.feature, x));
        const Real dist = std::sqrt(best);
        const bool behind = (p - c).dot(pn) < 0;
        // Out of the face's body: along p - c in front, c - p behind; the pseudo-normal on the surface.
        Vec3 n = dist > 1e-9 * F.thickness ? Vec3((behind ? c - p : p - c) / dist) : pn;
        if (n.squaredNorm() == 0) continue;
        out.push_back({v, uint32_t(b), tri, bestCp.w, n, behind ? -dist : dist});
      }
    }
}

}  // namespace gradel
