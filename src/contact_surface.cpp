#include "gradel/contact_surface.h"

#include <algorithm>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <vector>

#include "gradel/triangle_queries.h"

namespace gradel {

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

}  // namespace gradel
