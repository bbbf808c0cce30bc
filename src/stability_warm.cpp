#include "gradel/stability_warm.h"

#include <cmath>
#include <stdexcept>

#include "lcg.h"

namespace gradel {

std::vector<Vec3> stabilityWarmStart(const RestModel& oldModel, const RestModel& m, const std::vector<Vec3>& oldRitz,
                                     const std::vector<uint32_t>& fromVertex) {
  const size_t V = m.numVertices();
  if (fromVertex.size() != V || oldRitz.size() != oldModel.numVertices())
    throw std::invalid_argument("stabilityWarmStart: the vertex map or the Ritz vector does not fit the models");
  std::vector<Vec3> carried(V, Vec3::Zero());
  std::vector<uint8_t> changed(V, 0);
  for (size_t i = 0; i < V; ++i) {
    const uint32_t o = fromVertex[i];
    if (o == UINT32_MAX) {
      changed[i] = 1;
      continue;
    }
    if (o >= oldModel.numVertices()) throw std::invalid_argument("stabilityWarmStart: an old vertex id out of range");
    carried[i] = oldRitz[o];
    changed[i] = oldModel.mass[o] != m.mass[i];
  }
  // Grown by one element: every vertex of an element holding a changed vertex.
  std::vector<uint8_t> region(changed);
  for (size_t e = 0; e < m.numElements(); ++e) {
    bool any = false;
    for (uint32_t p = m.elemStart[e]; p < m.elemStart[e + 1] && !any; ++p) any = changed[m.elemVerts[p]];
    if (any)
      for (uint32_t p = m.elemStart[e]; p < m.elemStart[e + 1]; ++p) region[m.elemVerts[p]] = 1;
  }
  std::vector<Vec3> local(V, Vec3::Zero());
  Lcg r{0xD1B54A32D192ED03ull};
  for (size_t i = 0; i < V; ++i)
    if (region[i]) local[i] = Vec3(r.centred(), r.centred(), m.dim == 2 ? 0.0 : r.centred());
  double nc = 0, nl = 0;
  for (size_t i = 0; i < V; ++i) nc += carried[i].squaredNorm(), nl += local[i].squaredNorm();
  nc = std::sqrt(nc), nl = std::sqrt(nl);
  const double sc = nc > 0 ? 1 / nc : 0, sl = nl > 0 ? 1 / nl : 0;
  std::vector<Vec3> start(V);
  for (size_t i = 0; i < V; ++i) start[i] = sc * carried[i] + sl * local[i];
  return start;
}

}  // namespace gradel
