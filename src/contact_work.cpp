#include "gradel/contact_work.h"

#include <algorithm>

namespace gradel {

Real displacementWork(Real k, const Vec3& x0, const Vec3& xFree, const Vec3& x, Real surfaceTravel) {
  const Real d = std::max(Real(0), (x - xFree).norm() - (xFree - x0).norm() - surfaceTravel);
  return 0.5 * k * d * d;
}

std::vector<Real> vertexStiffness(const RestModel& model) {
  std::vector<Real> k(model.numVertices(), 0.0);
  for (size_t e = 0; e < model.numElements(); ++e)
    for (uint32_t p = model.elemStart[e]; p < model.elemStart[e + 1]; ++p) k[model.elemVerts[p]] += model.stiffness[e];
  return k;
}

}  // namespace gradel
