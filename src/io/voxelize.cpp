#include "gradel/io/voxelize.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace gradel::io {

namespace {

// One crossing of a ray with a triangle: which ray, where along it [voxels], and the change of
// the winding number after it.
struct Crossing {
  uint32_t ray;
  float t;
  int8_t delta;
};

struct P2 {
  double u, v;
};

// Orders crossings by ray, then along it: a counting sort by ray (linear), then each ray's few
// crossings by t. A comparison sort of all of them took most of a fuzz run's time.
void sortByRay(std::vector<Crossing>& crossings, std::vector<Crossing>& scratch, size_t rays) {
  std::vector<uint32_t> start(rays + 1, 0);
  for (const Crossing& c : crossings) ++start[c.ray + 1];
  for (size_t r = 0; r < rays; ++r) start[r + 1] += start[r];
  scratch.resize(crossings.size());
  for (const Crossing& c : crossings) scratch[start[c.ray]++] = c;  // start[r] ends at ray r's end
  crossings.swap(scratch);
  auto alongRay = [](const Crossing& a, const Crossing& b) { return a.t < b.t; };
  size_t b = 0;
  for (size_t r = 0; r < rays; ++r) {
    const size_t e = start[r];
    if (e - b > 1) std::sort(crossings.begin() + std::ptrdiff_t(b), crossings.begin() + std::ptrdiff_t(e), alongRay);
    b = e;
  }
}

bool lexLess(const P2& a, const P2& b) { return a.u < b.u || (a.u == b.u && a.v < b.v); }

// Edge function of P against the directed edge a -> b (> 0: P to the left). Evaluated with the
// endpoints in a canonical order and negated, so the two triangles sharing an edge get exactly
// opposite values, bit for bit.
double edgeFunction(const P2& a, const P2& b, const P2& p) {
  if (lexLess(b, a)) return -edgeFunction(b, a, p);
  return (b.u - a.u) * (p.v - a.v) - (b.v - a.v) * (p.u - a.u);
}

// Tie rule for a point exactly on edge a -> b of a counter-clockwise triangle: exactly one of
// the two directions of any edge owns it.
bool ownsEdge(const P2& a, const P2& b) {
  const double du = b.u - a.u, dv = b.v - a.v;
  return dv > 0 || (dv == 0 && du < 0);
}

}  // namespace

VoxelVolume voxelize(const TriangleMesh& mesh, const VoxelizeSettings& s, const std::string& name,
                     TriangleMesh* latticeMesh) {
  auto fail = [&](const std::string& what) { throw InputError(name + ": " + what); };
  if (s.resolution < 1 || s.resolution > 1024)
    fail("resolution " + std::to_string(s.resolution) + " (expected 1 to 1024 voxels)");
  if (mesh.triangles.empty()) fail("the mesh has no triangles");
  // The bounding box of the vertices the triangles use (each looked at once: a fan of 60000
  // triangles over four vertices must not cost 180000 vector operations).
  std::vector<uint8_t> used(mesh.vertices.size(), 0);
  for (const auto& t : mesh.triangles)
    for (uint32_t id : t) {
      if (id >= mesh.vertices.size()) fail("triangle vertex index " + std::to_string(id) + " out of range");
      used[id] = 1;
    }
  double bl[3], bh[3];
  for (int a = 0; a < 3; ++a) bl[a] = std::numeric_limits<double>::infinity(), bh[a] = -bl[a];
  for (size_t i = 0; i < used.size(); ++i) {
    if (!used[i]) continue;
    const double* p = mesh.vertices[i].data();
    for (int a = 0; a < 3; ++a) {
      if (!std::isfinite(p[a])) fail("a vertex is not finite");
      bl[a] = std::min(bl[a], p[a]);
      bh[a] = std::max(bh[a], p[a]);
    }
  }
  const Vec3 lo(bl[0], bl[1], bl[2]), hi(bh[0], bh[1], bh[2]);
  const Vec3 extent = hi - lo;
  const double longest = extent.maxCoeff();
  if (!std::isfinite(longest) || !(longest > 0)) fail("the mesh's bounding box is not a finite, non-empty box");
  const double h = longest / s.resolution;  // mesh units per voxel
  std::array<int, 3> n{};
  Vec3 origin;  // mesh point at lattice (0, 0, 0)
  for (int a = 0; a < 3; ++a) {
    n[a] = std::clamp(int(std::ceil(extent[a] / h - 1e-9)), 1, s.resolution);
    origin[a] = lo[a] - 0.5 * (n[a] * h - extent[a]);  // centred in its grid
  }
  VoxelVolume volume(3, n[0], n[1], n[2], s.voxelSize);
  std::vector<Vec3> lattice(mesh.vertices.size());
  for (size_t i = 0; i < mesh.vertices.size(); ++i) lattice[i] = (mesh.vertices[i] - origin) / h;

  // votes: low nibble = axes seeing winding != 0, high nibble = axes seeing 0.
  std::vector<uint8_t> votes(volume.size(), 0);
  std::vector<Crossing> crossings, sorted;
  for (int a = 0; a < 3; ++a) {
    const int u = (a + 1) % 3, v = (a + 2) % 3;  // (u, v, a) cyclic, so n_a = area in (u, v)
    crossings.clear();
    // A real surface crosses a ray a few times; thousands of overlapping sheets would only
    // exhaust memory and time, so the count per axis is capped (64 per ray on average).
    const size_t maxCrossings = std::max<size_t>(size_t(s.minCrossingCap), size_t(64) * size_t(n[u]) * size_t(n[v]));
    for (const auto& tri : mesh.triangles) {
      P2 p[3];
      double z[3];
      for (int k = 0; k < 3; ++k) {
        const Vec3& x = lattice[tri[k]];
        p[k] = {x[u], x[v]};
        z[k] = x[a];
      }
      const double area = edgeFunction(p[0], p[1], p[2]);
      if (area == 0) continue;  // parallel to the rays: no crossing
      // The ray runs along +a: a face whose normal has n_a < 0 (clockwise in (u, v)) is entered.
      const int8_t delta = area < 0 ? 1 : -1;
      if (area < 0) std::swap(p[1], p[2]), std::swap(z[1], z[2]);  // make it counter-clockwise
      const double uMin = std::min({p[0].u, p[1].u, p[2].u}), uMax = std::max({p[0].u, p[1].u, p[2].u});
      const double vMin = std::min({p[0].v, p[1].v, p[2].v}), vMax = std::max({p[0].v, p[1].v, p[2].v});
      const int iu0 = std::max(0, int(std::ceil(uMin - 0.5))), iu1 = std::min(n[u] - 1, int(std::floor(uMax - 0.5)));
      const int iv0 = std::max(0, int(std::ceil(vMin - 0.5))), iv1 = std::min(n[v] - 1, int(std::floor(vMax - 0.5)));
      for (int iv = iv0; iv <= iv1; ++iv) {
        // Only the cells near the triangle's span on this row are tested (a thin triangle across
        // the grid would otherwise test its whole bounding box): the span of the row's line
        // through the triangle, widened by a cell for rounding; the exact test below decides.
        const double vc = iv + 0.5;
        double sLo = std::numeric_limits<double>::infinity(), sHi = -sLo;
        for (int k = 0; k < 3; ++k) {
          const P2& e0 = p[k];
          const P2& e1 = p[(k + 1) % 3];
          if ((e0.v < vc) == (e1.v < vc) && e0.v != vc && e1.v != vc) continue;  // the line misses this edge
          const double f = e1.v == e0.v ? 0.0 : std::clamp((vc - e0.v) / (e1.v - e0.v), 0.0, 1.0);
          const double su = e0.u + f * (e1.u - e0.u);
          sLo = std::min({sLo, su, e1.v == e0.v ? e1.u : su});
          sHi = std::max({sHi, su, e1.v == e0.v ? e1.u : su});
        }
        if (!(sLo <= sHi)) continue;
        const int ju0 = std::max(iu0, int(std::ceil(sLo - 0.5)) - 1),
                  ju1 = std::min(iu1, int(std::floor(sHi - 0.5)) + 1);
        for (int iu = ju0; iu <= ju1; ++iu) {
          const P2 c{iu + 0.5, iv + 0.5};
          double w[3];
          bool inside = true;
          for (int k = 0; k < 3 && inside; ++k) {
            const P2& e0 = p[(k + 1) % 3];
            const P2& e1 = p[(k + 2) % 3];
            w[k] = edgeFunction(e0, e1, c);  // weight of vertex k
            inside = w[k] > 0 || (w[k] == 0 && ownsEdge(e0, e1));
          }
          if (!inside) continue;
          const double sum = w[0] + w[1] + w[2];
          const double t = (w[0] * z[0] + w[1] * z[1] + w[2] * z[2]) / sum;
          if (crossings.size() >= maxCrossings)
            fail("more than " + std::to_string(maxCrossings) +
                 " ray crossings: too many overlapping triangles for this resolution");
          crossings.push_back({uint32_t(iu + n[u] * iv), float(t), delta});
        }
      }
    }
    sortByRay(crossings, sorted, size_t(n[u]) * size_t(n[v]));
    // Every voxel first votes "outside" on this axis (a ray with no crossing is outside all
    // along); rays with crossings then change their voxels' votes.
    for (uint8_t& vote : votes) vote += 0x10;
    std::array<int, 3> idx{};
    for (size_t b = 0; b < crossings.size();) {
      size_t e = b;
      int total = 0;
      while (e < crossings.size() && crossings[e].ray == crossings[b].ray) total += crossings[e++].delta;
      const uint32_t ray = crossings[b].ray;
      idx[u] = int(ray % uint32_t(n[u]));
      idx[v] = int(ray / uint32_t(n[u]));
      int wind = 0;
      size_t c = b;
      for (int ia = 0; ia < n[a]; ++ia) {
        while (c < e && crossings[c].t < ia + 0.5) wind += crossings[c++].delta;
        idx[a] = ia;
        uint8_t& vote = votes[volume.index(idx[0], idx[1], idx[2])];
        vote -= 0x10;
        // Only a balanced ray (winding back to 0 at the far end) has a trustworthy winding number.
        if (total == 0) vote += wind != 0 ? 0x01 : 0x10;
      }
      b = e;
    }
  }
  uint8_t* out = volume.data().data();
  for (size_t i = 0; i < votes.size(); ++i) {
    const int in = votes[i] & 0x0f, outVotes = votes[i] >> 4;
    out[i] = in > outVotes ? 1 : 0;
  }
  if (volume.countFilled() == 0)
    fail("the voxelised volume is empty (an open mesh, or resolution " + std::to_string(s.resolution) +
         " too coarse for it)");
  if (latticeMesh) {
    latticeMesh->vertices = std::move(lattice);
    latticeMesh->triangles = mesh.triangles;
    latticeMesh->normals.clear();
  }
  return volume;
}

}  // namespace gradel::io
