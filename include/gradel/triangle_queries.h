// Point-triangle queries of body contacts (body_contacts.h): the closest point on a triangle and
// the winding number of a closed triangle surface.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "gradel/types.h"

namespace gradel {

/// Closest point on triangle (a, b, c) to p: barycentric weights (sum 1) and the feature it lies
/// on: 0 = inside the face, 1..3 = on an edge (1: ab, 2: bc, 3: ca), 4..6 = at a corner (a, b, c).
struct ClosestPoint {
  std::array<Real, 3> w;
  int feature;
};
ClosestPoint closestPointOnTriangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c);

/// Winding number of a closed triangle surface (world ids into x) about p: 1 inside, 0 outside
/// (the sum of the faces' signed solid angles / 4 pi). Exact for any surface, O(faces): for tests
/// and measurements, not the step.
Real windingNumber(const Vec3& p, const std::vector<std::array<uint32_t, 3>>& triangles, const Vec3* x);
}  // namespace gradel
