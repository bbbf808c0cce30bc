#include "gradel/contact_work.h"

#include <algorithm>

namespace gradel {

Real contactVertexWork(Real m, Real k, const Vec3& x0, const Vec3& v0, const Vec3& xFree, const Vec3& vFree,
                       const Vec3& x, const Vec3& v, Real dt) {
  const Vec3 dx = x - xFree;
  if (dx == Vec3::Zero() && v == vFree) return 0;
  const Vec3 a = (vFree - v0) / dt;
  const Real kinetic = 0.5 * m * (v.squaredNorm() - vFree.squaredNorm());
  const Real pressed = -m * a.dot(dx);
  const Real unexplained = std::max(Real(0), dx.norm() - (xFree - x0).norm());
  return kinetic + pressed + 0.5 * k * unexplained * unexplained;
}

std::vector<Real> vertexStiffness(const RestModel& model) {
  std::vector<Real> k(model.numVertices(), 0.0);
  for (size_t e = 0; e < model.numElements(); ++e)
    for (uint32_t p = model.elemStart[e]; p < model.elemStart[e + 1]; ++p) k[model.elemVerts[p]] += model.stiffness[e];
  return k;
}

}  // namespace gradel
