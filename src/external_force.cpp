#include "gradel/external_force.h"

#include <algorithm>

namespace gradel {

ExternalImpulse applyExternalImpulses(const std::vector<Vec3>& forces, const std::vector<Real>& masses,
                                      const std::vector<uint32_t>& pinned, Real dt, std::vector<Vec3>& velocities) {
  ExternalImpulse out;
  size_t nextPinned = 0;
  for (size_t i = 0; i < forces.size() && i < velocities.size(); ++i) {
    while (nextPinned < pinned.size() && pinned[nextPinned] < i) ++nextPinned;
    if (nextPinned < pinned.size() && pinned[nextPinned] == i) continue;
    const Vec3& f = forces[i];  // a 2D world's are in its plane (World::addExternalForces)
    if (f == Vec3::Zero()) continue;
    const Vec3 dv = f * (dt / masses[i]);
    out.work += masses[i] * (velocities[i].dot(dv) + 0.5 * dv.squaredNorm());
    out.impulse += f * dt;
    velocities[i] += dv;
  }
  return out;
}

}  // namespace gradel
