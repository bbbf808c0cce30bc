#include "gradel/overlaps.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "gradel/world.h"

namespace gradel {

BodyOccupancy::BodyOccupancy(const RestModel& model, const BodyRange& body) : origin_(body.origin), h_(body.voxelSize) {
  // Each element is a block of voxels: its vertices' rest box, in lattice units.
  std::vector<std::array<long, 6>> blocks;
  std::array<long, 3> lo{std::numeric_limits<long>::max(), std::numeric_limits<long>::max(),
                         std::numeric_limits<long>::max()},
      hi{std::numeric_limits<long>::min(), std::numeric_limits<long>::min(), std::numeric_limits<long>::min()};
  for (uint32_t e = body.elementBegin; e < body.elementEnd; ++e) {
    std::array<long, 6> b{std::numeric_limits<long>::max(), std::numeric_limits<long>::max(),
                          std::numeric_limits<long>::max(), std::numeric_limits<long>::min(),
                          std::numeric_limits<long>::min(), std::numeric_limits<long>::min()};
    for (uint32_t p = model.elemStart[e]; p < model.elemStart[e + 1]; ++p) {
      const Vec3 u = (model.restPositions[model.elemVerts[p]] - origin_) / h_;
      for (int a = 0; a < 3; ++a) {
        const long c = std::lround(u[a]);
        b[size_t(a)] = std::min(b[size_t(a)], c), b[size_t(a) + 3] = std::max(b[size_t(a) + 3], c);
      }
    }
    if (body.dim == 2) b[2] = -1, b[5] = 1;  // a 2D body: a slab around its plane
    for (int a = 0; a < 3; ++a) lo[size_t(a)] = std::min(lo[size_t(a)], b[size_t(a)]), hi[size_t(a)] = std::max(hi[size_t(a)], b[size_t(a) + 3]);
    blocks.push_back(b);
  }
  if (blocks.empty()) return;
  lo_ = lo;
  for (int a = 0; a < 3; ++a) n_[size_t(a)] = hi[size_t(a)] - lo[size_t(a)];
  cells_.assign(size_t(n_[0] * n_[1] * n_[2]), 0);
  for (const auto& b : blocks)
    for (long k = b[2]; k < b[5]; ++k)
      for (long j = b[1]; j < b[4]; ++j)
        for (long i = b[0]; i < b[3]; ++i)
          cells_[size_t(((k - lo_[2]) * n_[1] + (j - lo_[1])) * n_[0] + (i - lo_[0]))] = 1;
}

bool BodyOccupancy::occupied(long i, long j, long k) const {
  i -= lo_[0], j -= lo_[1], k -= lo_[2];
  if (i < 0 || j < 0 || k < 0 || i >= n_[0] || j >= n_[1] || k >= n_[2]) return false;
  return cells_[size_t((k * n_[1] + j) * n_[0] + i)] != 0;
}

bool BodyOccupancy::inside(const Vec3& p, const Vec3& shift) const {
  if (cells_.empty()) return false;
  const Vec3 u = (p - shift - origin_) / h_;
  if (!u.allFinite()) return false;
  constexpr Real eps = 1e-6;
  // Every cell within eps of the point: a point on a face of the body is not inside.
  for (int c = 0; c < 8; ++c) {
    const long i = long(std::floor(u.x() + (c & 1 ? eps : -eps)));
    const long j = long(std::floor(u.y() + (c & 2 ? eps : -eps)));
    const long k = long(std::floor(u.z() + (c & 4 ? eps : -eps)));
    if (!occupied(i, j, k)) return false;
  }
  return true;
}

namespace {
Manipulator scaled(const Manipulator& m, Real s) {
  Manipulator r = m;
  r.settings.radius *= s, r.settings.halfLength *= s;
  return r;
}
bool anyInside(const Manipulator& m, const Vec3* x, size_t n) {
  for (size_t i = 0; i < n; ++i) {
    if (m.signedDistance(x[i], nullptr) < 0) return true;
  }
  return false;
}
Vec3 centroid(const RestModel& model, const State& s, const BodyRange& b, Real* mass) {
  Vec3 c = Vec3::Zero();
  Real M = 0;
  for (uint32_t u = b.vertexBegin; u < b.vertexEnd; ++u) c += model.mass[u] * s.positions[u], M += model.mass[u];
  *mass = M;
  return M > 0 ? Vec3(c / M) : c;
}
}  // namespace

Real freeManipulatorScale(const Manipulator& m, const Vec3* x, size_t n) {
  if (!anyInside(m, x, n)) return 1;
  Real lo = 1e-6, hi = 1;
  if (anyInside(scaled(m, lo), x, n)) return lo;
  for (int it = 0; it < 50; ++it) {
    const Real mid = 0.5 * (lo + hi);
    (anyInside(scaled(m, mid), x, n) ? hi : lo) = mid;
  }
  return lo;
}

std::vector<StartOverlap> findStartOverlaps(const World& world) {
  const RestModel& model = world.model();
  const State& s = world.state();
  const int dim = model.dim;
  std::vector<StartOverlap> r;
  for (size_t b = 0; b < model.bodies.size(); ++b) {
    const BodyRange& body = model.bodies[b];
    if (world.domain().enabled) {
      const DomainSettings& d = world.domain();
      for (int w = 0; w < 2 * dim; ++w) {
        StartOverlap o{StartOverlap::With::Wall, b, size_t(w)};
        const int a = w / 2;
        for (uint32_t u = body.vertexBegin; u < body.vertexEnd; ++u) {
          const Real out = w % 2 == 0 ? d.min[a] - s.positions[u][a] : s.positions[u][a] - d.max[a];
          if (out > 0) o.depth = std::max(o.depth, out), ++o.vertices;
        }
        if (o.vertices) r.push_back(o);
      }
    }
    for (size_t k = 0; k < world.manipulators().size(); ++k) {
      const Manipulator& m = world.manipulators()[k];
      StartOverlap o{StartOverlap::With::Manipulator, b, k};
      for (uint32_t u = body.vertexBegin; u < body.vertexEnd; ++u) {
        const Real sd = m.signedDistance(s.positions[u], nullptr);
        if (sd < 0) o.depth = std::max(o.depth, -sd), ++o.vertices;
      }
      if (o.vertices) {
        o.scale = freeManipulatorScale(m, s.positions.data(), s.positions.size());
        const ManipulatorSettings& ms = m.settings;
        o.reach = ms.shape == ManipulatorShape::Cylinder ? std::max(ms.radius, ms.halfLength) : ms.radius;
        r.push_back(o);
      }
    }
  }
  if (dim != 3 || !world.bodyContacts()) return r;
  const size_t B = model.bodies.size();
  std::vector<Vec3> lo(B), hi(B), shift(B);
  for (size_t b = 0; b < B; ++b) {
    const BodyRange& body = model.bodies[b];
    lo[b] = Vec3::Constant(std::numeric_limits<Real>::infinity()), hi[b] = -lo[b];
    for (uint32_t u = body.vertexBegin; u < body.vertexEnd; ++u)
      lo[b] = lo[b].cwiseMin(s.positions[u]), hi[b] = hi[b].cwiseMax(s.positions[u]);
    // Where the body is now against its rest pose (a pin may have moved a few vertices: the mean).
    Vec3 d = Vec3::Zero();
    for (uint32_t u = body.vertexBegin; u < body.vertexEnd; ++u) d += s.positions[u] - model.restPositions[u];
    shift[b] = body.numVertices() ? Vec3(d / Real(body.numVertices())) : d;
  }
  for (size_t i = 0; i < B; ++i)
    for (size_t j = i + 1; j < B; ++j) {
      if ((lo[i].array() >= hi[j].array()).any() || (lo[j].array() >= hi[i].array()).any()) continue;
      const BodyRange &bi = model.bodies[i], &bj = model.bodies[j];
      size_t inside = 0;
      const BodyOccupancy oj(model, bj), oi(model, bi);
      for (uint32_t u = bi.vertexBegin; u < bi.vertexEnd; ++u)
        if (model.onSurface[u] && oj.inside(s.positions[u], shift[j])) ++inside;
      for (uint32_t u = bj.vertexBegin; u < bj.vertexEnd; ++u)
        if (model.onSurface[u] && oi.inside(s.positions[u], shift[i])) ++inside;
      if (!inside) continue;
      Real mi, mj;
      const Vec3 ci = centroid(model, s, bi, &mi), cj = centroid(model, s, bj, &mj);
      Vec3 n = cj - ci;
      n = n.norm() > 1e-9 * std::max(bi.voxelSize, bj.voxelSize) ? Vec3(n.normalized()) : Vec3(1, 0, 0);
      Real top = -std::numeric_limits<Real>::infinity(), bottom = std::numeric_limits<Real>::infinity();
      for (uint32_t u = bi.vertexBegin; u < bi.vertexEnd; ++u) top = std::max(top, s.positions[u].dot(n));
      for (uint32_t u = bj.vertexBegin; u < bj.vertexEnd; ++u) bottom = std::min(bottom, s.positions[u].dot(n));
      StartOverlap o{StartOverlap::With::Body, i, j};
      // Apart along n: no point of j below the highest point of i (at least a voxel for shapes
      // that interlock).
      o.depth = std::max(top - bottom, std::min(bi.voxelSize, bj.voxelSize));
      o.vertices = inside;
      o.direction = n;
      r.push_back(o);
    }
  return r;
}

std::string describeStartOverlap(const StartOverlap& o, const World& world, const std::vector<std::string>& names) {
  auto name = [&](size_t b) {
    return b < names.size() && !names[b].empty() ? "body '" + names[b] + "'" : "body " + std::to_string(b);
  };
  char buf[512];
  const Real h = world.model().bodies[o.body].voxelSize;
  const double seconds = o.depth / kStartSeparationSpeed;
  if (o.with == StartOverlap::With::Wall) {
    std::snprintf(buf, sizeof buf,
                  "warning: %s starts %.3g m (%.3g voxels) beyond the wall %s of the domain (%zu vertices): the wall "
                  "starts at the body and moves to its place at %g m/s, within %.3g s",
                  name(o.body).c_str(), o.depth, o.depth / h, wallName(int(o.other)), o.vertices,
                  kStartSeparationSpeed, seconds);
  } else if (o.with == StartOverlap::With::Manipulator) {
    const Real size = o.reach, free = o.scale;
    std::snprintf(buf, sizeof buf,
                  "warning: %s starts with %zu vertices inside manipulator %zu, up to %.3g m (%.3g voxels) deep: the "
                  "manipulator starts at %.3g of its size and grows back at %g m/s, within %.3g s",
                  name(o.body).c_str(), o.vertices, o.other, o.depth, o.depth / h, free, kStartSeparationSpeed,
                  (1 - free) * size / kStartSeparationSpeed);
  } else {
    std::snprintf(buf, sizeof buf,
                  "warning: %s and %s start overlapping (%zu surface vertices inside the other), by %.3g m (%.3g "
                  "voxels) along the line of their centres: moved apart at %g m/s without a change of velocity, "
                  "within %.3g s; contacts between bodies start then",
                  name(o.body).c_str(), name(o.other).c_str(), o.vertices, o.depth, o.depth / h,
                  kStartSeparationSpeed, seconds);
  }
  return buf;
}

}  // namespace gradel
