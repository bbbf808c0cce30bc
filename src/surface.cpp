#include "gradel/surface.h"

#include "gradel/display_normals.h"

#include <algorithm>
#include <map>
#include <stdexcept>
#include <unordered_map>

namespace gradel {

SurfaceKind parseSurfaceKind(const std::string& name) {
  if (name == "voxel") return SurfaceKind::Voxel;
  if (name == "smooth") return SurfaceKind::Smooth;
  throw InputError("unknown surface \"" + name + "\" (expected voxel or smooth)");
}

const char* surfaceKindName(SurfaceKind k) { return k == SurfaceKind::Voxel ? "voxel" : "smooth"; }

namespace {

using Pt2 = std::array<int32_t, 2>;
using Tri = std::array<uint32_t, 3>;

int64_t cross2(const Pt2& o, const Pt2& a, const Pt2& b) {
  return int64_t(a[0] - o[0]) * (b[1] - o[1]) - int64_t(a[1] - o[1]) * (b[0] - o[0]);
}

// Boundary loops of a union of axis-aligned squares (origin, edge `cell`) in a lattice plane,
// counter-clockwise, every unit lattice point listed. Where two squares touch only at a corner,
// the trace takes the leftmost turn, which keeps the two squares in separate loops.
std::vector<std::vector<Pt2>> squareLoops(const std::vector<Pt2>& squares, int32_t cell) {
  std::map<std::pair<Pt2, Pt2>, int> edges;  // directed edge -> present; opposite pairs cancel
  for (const Pt2& s : squares) {
    const Pt2 c[4] = {{s[0], s[1]}, {s[0] + cell, s[1]}, {s[0] + cell, s[1] + cell}, {s[0], s[1] + cell}};
    for (int i = 0; i < 4; ++i) {
      const Pt2 a = c[i], b = c[(i + 1) % 4];
      auto rev = edges.find({b, a});
      if (rev != edges.end())
        edges.erase(rev);
      else
        edges[{a, b}] = 1;
    }
  }
  std::multimap<Pt2, Pt2> out;
  for (const auto& [e, n] : edges) out.emplace(e.first, e.second);

  std::vector<std::vector<Pt2>> loops;
  while (!out.empty()) {
    auto it = out.begin();
    const Pt2 start = it->first;
    Pt2 a = it->first, b = it->second;
    out.erase(it);
    std::vector<Pt2> loop;
    for (;;) {
      const int32_t len = std::max(std::abs(b[0] - a[0]), std::abs(b[1] - a[1]));
      const Pt2 step = {(b[0] - a[0]) / len, (b[1] - a[1]) / len};
      for (int32_t k = 0; k < len; ++k) loop.push_back({a[0] + k * step[0], a[1] + k * step[1]});
      if (b == start) break;
      // Leftmost outgoing edge at b relative to the incoming direction.
      auto range = out.equal_range(b);
      auto best = out.end();
      int bestRank = 9;
      for (auto o = range.first; o != range.second; ++o) {
        const int64_t turn = int64_t(step[0]) * (o->second[1] - b[1]) - int64_t(step[1]) * (o->second[0] - b[0]);
        const int rank = turn > 0 ? 0 : (turn == 0 ? 1 : 2);
        if (rank < bestRank) bestRank = rank, best = o;
      }
      if (best == out.end()) throw std::logic_error("squareLoops: open boundary");
      a = b;
      b = best->second;
      out.erase(best);
    }
    loops.push_back(std::move(loop));
  }
  return loops;
}

// Ear clipping of a simple counter-clockwise polygon that may have collinear points. Only
// strictly convex ears with no other point inside or on them are cut, so no triangle is
// degenerate and no point is left on another triangle's edge.
std::vector<std::array<size_t, 3>> earClip(const std::vector<Pt2>& poly) {
  std::vector<size_t> idx(poly.size());
  for (size_t i = 0; i < idx.size(); ++i) idx[i] = i;
  std::vector<std::array<size_t, 3>> tris;
  auto inside = [&](const Pt2& p, const Pt2& a, const Pt2& b, const Pt2& c) {
    return cross2(a, b, p) >= 0 && cross2(b, c, p) >= 0 && cross2(c, a, p) >= 0;
  };
  while (idx.size() > 3) {
    bool cut = false;
    for (size_t k = 0; k < idx.size() && !cut; ++k) {
      const size_t ip = idx[(k + idx.size() - 1) % idx.size()], ic = idx[k], in = idx[(k + 1) % idx.size()];
      if (cross2(poly[ip], poly[ic], poly[in]) <= 0) continue;
      bool empty = true;
      for (size_t j : idx)
        if (j != ip && j != ic && j != in && poly[j] != poly[ip] && poly[j] != poly[ic] && poly[j] != poly[in] &&
            inside(poly[j], poly[ip], poly[ic], poly[in])) {
          empty = false;
          break;
        }
      if (!empty) continue;
      tris.push_back({ip, ic, in});
      idx.erase(idx.begin() + std::ptrdiff_t(k));
      cut = true;
    }
    if (!cut) throw std::logic_error("earClip: no ear in a lattice polygon");
  }
  if (cross2(poly[idx[0]], poly[idx[1]], poly[idx[2]]) > 0) tris.push_back({idx[0], idx[1], idx[2]});
  return tris;
}

// Collects surface vertices (one per model vertex used) and triangles.
class SurfaceBuilder {
 public:
  explicit SurfaceBuilder(const Layout& layout) : layout_(layout) {}

  bool isVertex(const Int3& p) const { return layout_.vertexAt(p) != Layout::kNoVertex; }

  // Adds the squares' region in the plane {axis = w}, u = (axis+1)%3, v = (axis+2)%3, facing
  // +axis (flip = false) or -axis.
  void addRegion(const std::vector<Pt2>& squares, int32_t cell, int axis, int32_t w, bool flip) {
    const int ua = (axis + 1) % 3, va = (axis + 2) % 3;
    auto to3 = [&](const Pt2& q) {
      Int3 p;
      p[axis] = w;
      p[ua] = q[0];
      p[va] = q[1];
      return p;
    };
    for (const std::vector<Pt2>& loop : squareLoops(squares, cell)) {
      std::vector<Pt2> poly;
      for (size_t i = 0; i < loop.size(); ++i) {
        if (isVertex(to3(loop[i]))) {
          poly.push_back(loop[i]);
          continue;
        }
        const Pt2& a = loop[(i + loop.size() - 1) % loop.size()];
        const Pt2& b = loop[(i + 1) % loop.size()];
        if (cross2(a, loop[i], b) != 0)
          throw std::logic_error("display surface: a polygon corner is not a model vertex");
      }
      for (const auto& t : earClip(poly)) {
        Tri tri = {surfaceId(to3(poly[t[0]])), surfaceId(to3(poly[t[1]])), surfaceId(to3(poly[t[2]]))};
        if (flip) std::swap(tri[1], tri[2]);
        out_.triangles.push_back(tri);
      }
    }
  }

  DisplaySurface& result() { return out_; }

 private:
  uint32_t surfaceId(const Int3& p) {
    const uint32_t model = layout_.vertexAt(p);
    if (model == Layout::kNoVertex) throw std::logic_error("display surface: a triangle corner is not a model vertex");
    auto [it, added] = local_.emplace(model, uint32_t(out_.modelVertex.size()));
    if (added) out_.modelVertex.push_back(model);
    return it->second;
  }

  const Layout& layout_;                          // lattice point -> model vertex (vertexAt)
  std::unordered_map<uint32_t, uint32_t> local_;  // model vertex -> surface vertex
  DisplaySurface out_;
};

// 3D: the exposed voxel faces of each element, one flat region per (plane, facing). Only
// finest-level elements hold surface voxels (sec. 3.2 step 1), so only their cells are visited.
void addVoxelFaces3D(const Layout& layout, const VoxelVolume& volume, SurfaceBuilder& b) {
  struct Group {
    int axis, sign;
    int32_t w;
    std::vector<Pt2> squares;
  };
  for (size_t e = 0; e < layout.numElements(); ++e) {
    if (layout.cellSize[e] != 1) continue;
    std::vector<Group> groups;
    for (int c = 0; c < 8; ++c) {
      if (!(layout.cellMask[e] >> c & 1)) continue;
      const Int3 p = layout.origin[e] + Int3(c & 1, c >> 1 & 1, c >> 2 & 1);
      for (int axis = 0; axis < 3; ++axis)
        for (int sign = -1; sign <= 1; sign += 2) {
          Int3 q = p;
          q[axis] += sign;
          if (volume.at(q.x(), q.y(), q.z())) continue;
          const int32_t w = p[axis] + (sign > 0 ? 1 : 0);
          auto g = std::find_if(groups.begin(), groups.end(),
                                [&](const Group& x) { return x.axis == axis && x.sign == sign && x.w == w; });
          if (g == groups.end()) g = groups.insert(groups.end(), Group{axis, sign, w, {}});
          g->squares.push_back({p[(axis + 1) % 3], p[(axis + 2) % 3]});
        }
    }
    for (const Group& g : groups) b.addRegion(g.squares, 1, g.axis, g.w, g.sign < 0);
  }
}

// 2D: each element's region (its filled cells) in the z = 0 plane, facing +z.
void addRegions2D(const Layout& layout, SurfaceBuilder& b) {
  for (size_t e = 0; e < layout.numElements(); ++e) {
    std::vector<Pt2> squares;
    const int32_t c = layout.cellSize[e];
    for (int k = 0; k < 4; ++k)
      if (layout.cellMask[e] >> k & 1)
        squares.push_back({layout.origin[e].x() + (k & 1) * c, layout.origin[e].y() + (k >> 1 & 1) * c});
    b.addRegion(squares, c, 2, 0, false);
  }
}

uint64_t edgeKey(uint32_t a, uint32_t b) { return uint64_t(a) << 32 | b; }

Vec3 triNormal(const std::vector<Vec3>& x, const Tri& t) { return (x[t[1]] - x[t[0]]).cross(x[t[2]] - x[t[0]]); }

// Lays faces over concave steps (fig. 7): flips every concave edge between two triangles to the
// other diagonal, as long as the flip makes no duplicate edge and no folded or flat triangle.
// Positions are the rest lattice, so the decisions are exact.
void flipConcaveEdges(std::vector<Tri>& tris, const std::vector<Vec3>& x) {
  std::unordered_map<uint64_t, uint32_t> edgeTri;  // directed edge -> triangle
  std::unordered_map<uint64_t, int> edgeCount;
  for (uint32_t t = 0; t < tris.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      const uint64_t key = edgeKey(tris[t][k], tris[t][(k + 1) % 3]);
      edgeTri[key] = t;
      ++edgeCount[key];
    }
  auto third = [](const Tri& t, uint32_t a, uint32_t b) {
    for (uint32_t v : t)
      if (v != a && v != b) return v;
    return a;
  };
  constexpr int kMaxPasses = 16;
  for (int pass = 0; pass < kMaxPasses; ++pass) {
    // Deepest folds first (then by vertex ids, for a deterministic order): each flip changes
    // its neighbours' folds, and covering the deepest step first gives the evenest surface.
    struct Candidate {
      Real depth;
      uint32_t a, b;
    };
    std::vector<Candidate> candidates;
    for (const auto& [key, t] : edgeTri) {
      const uint32_t a = uint32_t(key >> 32), b = uint32_t(key);
      auto rev = edgeTri.find(edgeKey(b, a));
      if (a > b || rev == edgeTri.end()) continue;
      const Vec3 n1 = triNormal(x, tris[t]).normalized();
      const Real depth = (x[third(tris[rev->second], a, b)] - x[a]).dot(n1);
      if (depth > 1e-12) candidates.push_back({depth, a, b});
    }
    std::sort(candidates.begin(), candidates.end(), [](const Candidate& p, const Candidate& q) {
      return p.depth != q.depth ? p.depth > q.depth : std::pair(p.a, p.b) < std::pair(q.a, q.b);
    });
    size_t flips = 0;
    for (const auto& [depth, a, b] : candidates) {
      auto i1 = edgeTri.find(edgeKey(a, b)), i2 = edgeTri.find(edgeKey(b, a));
      if (i1 == edgeTri.end() || i2 == edgeTri.end()) continue;
      if (edgeCount[edgeKey(a, b)] != 1 || edgeCount[edgeKey(b, a)] != 1) continue;  // non-manifold edge
      const uint32_t t1 = i1->second, t2 = i2->second;
      const uint32_t c = third(tris[t1], a, b), d = third(tris[t2], a, b);
      if (c == d || edgeTri.count(edgeKey(c, d)) || edgeTri.count(edgeKey(d, c))) continue;
      const Vec3 n1 = triNormal(x, tris[t1]), n2 = triNormal(x, tris[t2]);
      if ((x[d] - x[a]).dot(n1) <= 1e-12) continue;  // convex or flat: nothing to cover
      const Tri u1 = {a, d, c}, u2 = {d, b, c};
      const Vec3 m1 = triNormal(x, u1), m2 = triNormal(x, u2), avg = n1.normalized() + n2.normalized();
      if (m1.squaredNorm() < 1e-18 || m2.squaredNorm() < 1e-18 || m1.dot(avg) <= 0 || m2.dot(avg) <= 0) continue;
      // Drop the old edges of the pair, then register the new pair.
      for (const Tri& t : {tris[t1], tris[t2]})
        for (int k = 0; k < 3; ++k) {
          const uint64_t key = edgeKey(t[k], t[(k + 1) % 3]);
          edgeTri.erase(key);
          edgeCount.erase(key);
        }
      tris[t1] = u1;
      tris[t2] = u2;
      for (uint32_t t : {t1, t2})
        for (int k = 0; k < 3; ++k) {
          const uint64_t key = edgeKey(tris[t][k], tris[t][(k + 1) % 3]);
          edgeTri[key] = t;
          edgeCount[key] = 1;
        }
      ++flips;
    }
    if (flips == 0) break;
  }
}

// 2D: a triangle over every concave corner of the outline (never two in a row, so they do not
// overlap).
void coverConcaveCorners2D(std::vector<Tri>& tris, const std::vector<Vec3>& x) {
  std::unordered_map<uint64_t, int> directed;
  for (const Tri& t : tris)
    for (int k = 0; k < 3; ++k) ++directed[edgeKey(t[k], t[(k + 1) % 3])];
  std::map<uint32_t, std::vector<uint32_t>> next, prev;
  for (const auto& [key, n] : directed) {
    const uint32_t a = uint32_t(key >> 32), b = uint32_t(key);
    if (directed.count(edgeKey(b, a))) continue;
    next[a].push_back(b);
    prev[b].push_back(a);
  }
  std::vector<Tri> added;
  std::vector<uint32_t> covered;
  for (const auto& [v, ns] : next) {
    if (ns.size() != 1 || prev[v].size() != 1) continue;  // pinch point: leave it
    const uint32_t p = prev[v][0], n = ns[0];
    const Vec3 d1 = x[v] - x[p], d2 = x[n] - x[v];
    if (d1.x() * d2.y() - d1.y() * d2.x() >= -1e-12) continue;  // convex or straight
    if (std::find(covered.begin(), covered.end(), p) != covered.end() ||
        std::find(covered.begin(), covered.end(), n) != covered.end())
      continue;
    added.push_back({p, n, v});
    covered.push_back(v);
  }
  tris.insert(tris.end(), added.begin(), added.end());
}

}  // namespace

DisplaySurface buildDisplaySurface(const Layout& layout, const VoxelVolume& volume, SurfaceKind kind) {
  SurfaceBuilder b(layout);
  if (layout.dim == 3)
    addVoxelFaces3D(layout, volume, b);
  else
    addRegions2D(layout, b);
  DisplaySurface s = std::move(b.result());
  s.dim = layout.dim;
  s.kind = kind;
  if (kind == SurfaceKind::Smooth) {
    std::vector<Vec3> rest(s.modelVertex.size());
    for (size_t i = 0; i < rest.size(); ++i) rest[i] = layout.vertices[s.modelVertex[i]].cast<Real>();
    if (layout.dim == 3) {
      flipConcaveEdges(s.triangles, rest);
      s.restMeshNormals = smoothVertexNormals(rest, s.triangles);
      s.restFieldNormals = fieldNormals(volume, rest, displayNormalSigma(volume));
    } else {
      coverConcaveCorners2D(s.triangles, rest);
    }
  }
  return s;
}

std::vector<Vec3> vertexNormals(const std::vector<Vec3>& vertices,
                                const std::vector<std::array<uint32_t, 3>>& triangles) {
  std::vector<Vec3> n(vertices.size(), Vec3::Zero());
  // The unnormalised cross product weights each face by its area.
  for (const auto& t : triangles) {
    const Vec3 f = (vertices[t[1]] - vertices[t[0]]).cross(vertices[t[2]] - vertices[t[0]]);
    for (uint32_t v : t) n[v] += f;
  }
  for (Vec3& v : n) {
    const Real len = v.norm();
    v = len > 0 ? Vec3(v / len) : Vec3(0, 0, 1);
  }
  return n;
}

std::vector<Vec3> smoothVertexNormals(const std::vector<Vec3>& vertices,
                                      const std::vector<std::array<uint32_t, 3>>& triangles) {
  // Averaged from the neighbouring faces, then once more over the neighbouring vertices: the
  // faces laid over the steps are small and tilted every which way, and one average still
  // shows each of them.
  const std::vector<Vec3> n1 = vertexNormals(vertices, triangles);
  std::vector<Vec3> n2 = n1;
  for (const auto& t : triangles)
    for (int k = 0; k < 3; ++k) n2[t[size_t(k)]] += n1[t[size_t((k + 1) % 3)]] + n1[t[size_t((k + 2) % 3)]];
  for (Vec3& n : n2) {
    const Real len = n.norm();
    n = len > 0 ? Vec3(n / len) : Vec3(0, 0, 1);
  }
  return n2;
}

TriangleMesh surfaceMesh(const DisplaySurface& surface, const std::vector<Vec3>& positions) {
  TriangleMesh m;
  m.vertices.resize(surface.modelVertex.size());
  for (size_t i = 0; i < m.vertices.size(); ++i) m.vertices[i] = positions[surface.modelVertex[i]];
  m.triangles = surface.triangles;
  if (surface.dim == 3 && surface.kind == SurfaceKind::Smooth) {
    m.normals = smoothVertexNormals(m.vertices, m.triangles);
    if (!surface.restFieldNormals.empty())
      m.normals = carryNormals(m.normals, surface.restMeshNormals, surface.restFieldNormals);
  } else if (surface.dim == 3) {
    m.normals = vertexNormals(m.vertices, m.triangles);
  } else
    m.normals.assign(m.vertices.size(), Vec3(0, 0, 1));
  return m;
}

}  // namespace gradel

namespace gradel {

void shiftVertexIds(DisplaySurface& surface, uint32_t offset) {
  for (uint32_t& v : surface.modelVertex) v += offset;
}

}  // namespace gradel
