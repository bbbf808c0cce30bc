// How far a body moved in a step and since the body-contact tracks' last rebuild (the broad
// phase's bounds, body_contacts.h): measured by the stage, or by an explicit step in its own
// vertex pass and handed in.
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>

#include "gradel/types.h"

namespace gradel {

/// A vertex's position at the tracks' last rebuild, rounded to float (x, y, z, 0): half the bytes
/// a step streams to measure how far it has moved since; the stage adds the rounding back.
using RefPoint = std::array<float, 4>;

/// How far a body moved, what the stage's first pass measures (BodyContacts::measure): per axis,
/// the largest square of a vertex's coordinate difference between the end of the step and its
/// start (moved2) and between the end of the step and its RefPoint (since2;
/// BodyContacts::referencePositions()), over every vertex of the body (its surface moves no
/// farther). An explicit step measures it in its own vertex pass, where the positions are at hand
/// (World::stageVertices), and hands it in (BodyContactState::motion).
struct BodyMotion {
  std::array<Real, 3> moved2{0, 0, 0};  ///< [m^2]
  std::array<Real, 3> since2{0, 0, 0};  ///< [m^2]
  void add(const BodyMotion& m) {
    for (int a = 0; a < 3; ++a)
      moved2[size_t(a)] = std::max(moved2[size_t(a)], m.moved2[size_t(a)]),
      since2[size_t(a)] = std::max(since2[size_t(a)], m.since2[size_t(a)]);
  }
};

/// Adds vertices [begin, end) to m: x the end of the step, x0 its start, ref the rebuild's
/// positions (world ids). A NaN difference is left out (max keeps the larger of two numbers).
inline void addMotion(const Vec3* x, const Vec3* x0, const RefPoint* ref, size_t begin, size_t end, BodyMotion& m) {
  for (size_t u = begin; u < end; ++u)
    for (int a = 0; a < 3; ++a) {
      const Real d = x[u][a] - x0[u][a], e = x[u][a] - Real(ref[u][size_t(a)]);
      m.moved2[size_t(a)] = d * d > m.moved2[size_t(a)] ? d * d : m.moved2[size_t(a)];
      m.since2[size_t(a)] = e * e > m.since2[size_t(a)] ? e * e : m.since2[size_t(a)];
    }
}

}  // namespace gradel
