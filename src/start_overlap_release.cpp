// Start overlaps (overlaps.h): found once at t = 0, then released step by step (walls moved
// back, manipulators grown back, overlapping bodies moved apart at kStartSeparationSpeed).
#include <algorithm>
#include <cmath>
#include <limits>

#include "gradel/overlaps.h"
#include "step_context.h"

namespace gradel {

// Start overlaps (overlaps.h): the walls are moved out to the bodies, the manipulators shrunk
// until no vertex is inside, and the overlapping pairs of bodies listed; every step then takes
// each back by at most kStartSeparationSpeed dt.
void World::releaseStartOverlaps() {
  domain_ = domainSet_ = separatingStartOverlaps() ? domainSet_ : domain_;
  wallsReleasing_ = false;
  separations_.clear();
  for (size_t k = 0; k < manipulatorScale_.size() && k < manipulators_.size(); ++k)
    manipulators_[k].settings.radius = manipulatorSize_[k][0], manipulators_[k].settings.halfLength = manipulatorSize_[k][1];
  domainSet_ = domain_;
  manipulatorScale_.assign(manipulators_.size(), 1.0);
  manipulatorSize_.clear();
  for (const Manipulator& m : manipulators_) manipulatorSize_.push_back({m.settings.radius, m.settings.halfLength});
  startOverlaps_ = findStartOverlaps(*this);
  const std::vector<StartOverlap>& overlaps = startOverlaps_;
  if (overlaps.empty()) return;
  const RestModel& rm = *model_;
  std::vector<uint8_t> pinnedBody(rm.bodies.size(), 0);
  for (uint32_t u : pinSet_.vertices)
    for (size_t b = 0; b < rm.bodies.size(); ++b)
      if (u >= rm.bodies[b].vertexBegin && u < rm.bodies[b].vertexEnd) pinnedBody[b] = 1;
  for (const StartOverlap& o : overlaps) {
    if (o.with == StartOverlap::With::Wall) {
      const int a = int(o.other) / 2;
      if (o.other % 2 == 0)
        domain_.min[a] = std::min(domain_.min[a], domainSet_.min[a] - o.depth);
      else
        domain_.max[a] = std::max(domain_.max[a], domainSet_.max[a] + o.depth);
      wallsReleasing_ = true;
    } else if (o.with == StartOverlap::With::Manipulator) {
      Real& scale = manipulatorScale_[o.other];
      if (scale < 1) continue;  // (found for all bodies' vertices at once)
      Manipulator& m = manipulators_[o.other];
      scale = freeManipulatorScale(m, state_.positions.data(), state_.positions.size());
      m.settings.radius = scale * manipulatorSize_[o.other][0];
      m.settings.halfLength = scale * manipulatorSize_[o.other][1];
    } else if (!pinnedBody[o.body] || !pinnedBody[o.other]) {
      Separation sep;
      sep.a = uint32_t(o.body), sep.b = uint32_t(o.other), sep.direction = o.direction, sep.remaining = o.depth;
      Real ma = 0, mb = 0;
      for (uint32_t u = rm.bodies[o.body].vertexBegin; u < rm.bodies[o.body].vertexEnd; ++u) ma += rm.mass[u];
      for (uint32_t u = rm.bodies[o.other].vertexBegin; u < rm.bodies[o.other].vertexEnd; ++u) mb += rm.mass[u];
      // The centre of mass stays: a moves mb / (ma + mb) of the way, b the rest; a pinned body stays.
      sep.weightA = pinnedBody[o.body] ? 0 : pinnedBody[o.other] ? 1 : mb / (ma + mb);
      sep.weightB = 1 - sep.weightA;
      separations_.push_back(sep);
    }
  }
}

void World::advanceStartOverlapRelease() {
  const Real step = kStartSeparationSpeed * dt_;
  wallVelocity_.fill(Vec3::Zero());
  if (wallsReleasing_) {
    wallsReleasing_ = false;
    for (int a = 0; a < 3; ++a) {
      const Real lo = std::min(domainSet_.min[a], domain_.min[a] + step);
      const Real hi = std::max(domainSet_.max[a], domain_.max[a] - step);
      wallVelocity_[size_t(2 * a)][a] = (lo - domain_.min[a]) / dt_;
      wallVelocity_[size_t(2 * a + 1)][a] = (hi - domain_.max[a]) / dt_;
      domain_.min[a] = lo, domain_.max[a] = hi;
      wallsReleasing_ = wallsReleasing_ || domain_.min[a] != domainSet_.min[a] || domain_.max[a] != domainSet_.max[a];
    }
  }
  manipulatorGrowth_.assign(manipulators_.size(), 0.0);
  for (size_t k = 0; k < manipulatorScale_.size() && k < manipulators_.size(); ++k) {
    Real& scale = manipulatorScale_[k];
    if (scale >= 1) continue;
    manipulatorGrowth_[k] = kStartSeparationSpeed;
    const auto& size = manipulatorSize_[k];
    const Real reach = manipulators_[k].settings.shape == ManipulatorShape::Cylinder ? std::max(size[0], size[1]) : size[0];
    scale = std::min(Real(1), scale + step / reach);
    manipulators_[k].settings.radius = scale < 1 ? scale * size[0] : size[0];
    manipulators_[k].settings.halfLength = scale < 1 ? scale * size[1] : size[1];
  }
  const RestModel& rm = *model_;
  // Each pair's overlap along its direction is measured again every step (the bodies move
  // meanwhile): they are moved apart by at most kStartSeparationSpeed dt plus the speed at
  // which they close, until the extents no longer overlap.
  for (Separation& sep : separations_) {
    const BodyRange &A = rm.bodies[sep.a], &B = rm.bodies[sep.b];
    Real top = -std::numeric_limits<Real>::infinity(), bottom = std::numeric_limits<Real>::infinity();
    Vec3 va = Vec3::Zero(), vb = Vec3::Zero();
    Real ma = 0, mb = 0;
    for (uint32_t u = A.vertexBegin; u < A.vertexEnd; ++u)
      top = std::max(top, state_.positions[u].dot(sep.direction)), va += rm.mass[u] * state_.velocities[u],
      ma += rm.mass[u];
    for (uint32_t u = B.vertexBegin; u < B.vertexEnd; ++u)
      bottom = std::min(bottom, state_.positions[u].dot(sep.direction)), vb += rm.mass[u] * state_.velocities[u],
      mb += rm.mass[u];
    const Real closing = std::max(Real(0), (va / ma - vb / mb).dot(sep.direction));
    sep.remaining = std::isfinite(top - bottom) ? top - bottom : 0;
    const Real d = std::min(step + closing * dt_, sep.remaining);
    if (d <= 0) continue;
    sep.remaining -= d;
    const Vec3 da = -sep.weightA * d * sep.direction, db = sep.weightB * d * sep.direction;
    for (uint32_t u = A.vertexBegin; u < A.vertexEnd; ++u) state_.positions[u] += da;
    for (uint32_t u = B.vertexBegin; u < B.vertexEnd; ++u) state_.positions[u] += db;
  }
  separations_.erase(std::remove_if(separations_.begin(), separations_.end(),
                                    [](const Separation& s) { return s.remaining <= 0; }),
                     separations_.end());
}

}  // namespace gradel
