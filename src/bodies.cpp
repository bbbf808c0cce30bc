#include "gradel/bodies.h"

#include <algorithm>
#include <limits>
#include <stdexcept>

namespace gradel {

RestModel combineRestModels(const std::vector<std::shared_ptr<const RestModel>>& models) {
  if (models.empty()) throw std::invalid_argument("combineRestModels: no model");
  size_t V = 0, E = 0, P = 0;
  for (const auto& m : models) {
    if (!m) throw std::invalid_argument("combineRestModels: a null model");
    if (m->dim != models[0]->dim) throw std::invalid_argument("combineRestModels: models of different dim");
    V += m->numVertices(), E += m->numElements(), P += m->numPairs();
  }
  constexpr size_t kMax = std::numeric_limits<uint32_t>::max();
  if (V >= kMax || E >= kMax || P >= kMax)
    throw std::invalid_argument("combineRestModels: more than 2^32 - 1 vertices, elements or pairs");

  const RestModel& first = *models[0];
  RestModel c;
  c.dim = first.dim;
  c.voxelSize = first.voxelSize, c.material = first.material, c.origin = first.origin;
  auto reserve = [](auto& v, size_t n) { v.reserve(n); };
  reserve(c.restPositions, V), reserve(c.mass, V), reserve(c.invMass, V), reserve(c.onSurface, V);
  reserve(c.stiffness, E), reserve(c.size, E), reserve(c.level, E), reserve(c.elementMaterial, E), reserve(c.elemStart, E + 1);
  reserve(c.elemVerts, P), reserve(c.restCentroids, E);
  auto append = [](auto& to, const auto& from) { to.insert(to.end(), from.begin(), from.end()); };
  c.elemStart.push_back(0);
  c.smallestPeriod = std::numeric_limits<Real>::infinity();
  c.smallestVertexPeriod = std::numeric_limits<Real>::infinity();
  const bool anyVolumeTerm = std::any_of(models.begin(), models.end(), [](const auto& m) { return m->hasVolumeTerm(); });
  const bool anyRegionDamping =
      std::any_of(models.begin(), models.end(), [](const auto& m) { return m->hasRegionDamping(); });
  for (const auto& mp : models) {
    const RestModel& m = *mp;
    const uint32_t v0 = uint32_t(c.numVertices()), e0 = uint32_t(c.numElements()), p0 = uint32_t(c.numPairs());
    append(c.restPositions, m.restPositions), append(c.mass, m.mass), append(c.invMass, m.invMass);
    append(c.onSurface, m.onSurface);
    append(c.stiffness, m.stiffness), append(c.size, m.size), append(c.level, m.level);
    // Volumetric terms (model.h): a model without one has kappa 0 on its elements.
    if (anyVolumeTerm) {
      if (m.hasVolumeTerm())
        append(c.volumeStiffness, m.volumeStiffness);
      else
        c.volumeStiffness.resize(c.numElements(), 0);
    }
    for (size_t e = 1; e < m.elemStart.size(); ++e) c.elemStart.push_back(p0 + m.elemStart[e]);
    for (uint32_t v : m.elemVerts) c.elemVerts.push_back(v0 + v);
    append(c.restCentroids, m.restCentroids);
    // Materials per region (model.h): each model's table appended, its element indices offset.
    if (c.materials.size() + m.materials.size() > 65535)
      throw std::invalid_argument("combineRestModels: more than 65535 materials");
    const uint16_t k0 = uint16_t(c.materials.size());
    append(c.materials, m.materials), append(c.materialLabel, m.materialLabel);
    for (uint16_t k : m.elementMaterial) c.elementMaterial.push_back(uint16_t(k0 + k));
    // A model made by hand, without bodies, is one body.
    for (BodyRange b : m.bodies.empty() ? std::vector<BodyRange>{wholeModelBody(m)} : m.bodies) {
      b.vertexBegin += v0, b.vertexEnd += v0, b.elementBegin += e0, b.elementEnd += e0;
      c.bodies.push_back(b);
    }
    // Damping per region (model.h): a model without its own rates takes the simulation's everywhere.
    if (anyRegionDamping) {
      if (m.hasRegionDamping())
        append(c.dampingOwn, m.dampingOwn), append(c.dampingDefaultShare, m.dampingDefaultShare);
      else
        c.dampingOwn.resize(c.numVertices(), 0), c.dampingDefaultShare.resize(c.numVertices(), 1);
    }
    c.smallestPeriod = std::min(c.smallestPeriod, m.smallestPeriod);
    c.smallestVertexPeriod = std::min(c.smallestVertexPeriod, m.smallestVertexPeriod);
  }
  // The same order of summation as buildRestModel's (every vertex in id order): one model's
  // total is reproduced exactly.
  for (Real m : c.mass) c.totalMass += m;
  return c;
}

}  // namespace gradel
