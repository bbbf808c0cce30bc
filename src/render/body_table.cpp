#include "gradel/render/body_table.h"

namespace gradel::render {

std::vector<BodyRow> bodyTable(const BuiltScene& scene) {
  const World& w = *scene.world;
  const RestModel& m = w.model();
  const std::vector<Metrics> metrics = w.bodyMetrics();
  std::vector<BodyRow> rows;
  for (size_t i = 0; i < scene.numBodies() && i < metrics.size(); ++i) {
    const BodyRange& b = scene.range(i);
    BodyRow r;
    r.name = scene.bodies[i].name;
    r.vertices = b.numVertices(), r.elements = b.numElements();
    Vec3 moment = Vec3::Zero();
    for (uint32_t v = b.vertexBegin; v < b.vertexEnd; ++v)
      r.mass += m.mass[v], moment += m.mass[v] * w.state().positions[v];
    if (r.mass > 0) r.centre = moment / r.mass, r.velocity = metrics[i].linearMomentum / r.mass;
    r.kineticEnergy = metrics[i].kineticEnergy, r.elasticEnergy = metrics[i].elasticEnergy;
    r.maxStress = metrics[i].maxStress;
    rows.push_back(std::move(r));
  }
  return rows;
}

}  // namespace gradel::render
