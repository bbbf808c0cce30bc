#include "gradel/triangle_queries.h"

#include <cmath>

namespace gradel {

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

}  // namespace gradel
