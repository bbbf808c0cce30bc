// Carving in a built scene: carveBody per body, then the world made again once (carve_scene.h).
#include "gradel/carve_scene.h"

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <stdexcept>
#include <utility>
#include <vector>

#include "gradel/bodies.h"
#include "gradel/contact_surface.h"

namespace gradel {

namespace {

// The bodies' events (body index, mask), at most one per body; the world replaced once.
std::vector<CarveEvent> carveBodies(BuiltScene& scene, const std::vector<std::pair<size_t, std::vector<uint8_t>>>& masks) {
  World& world = *scene.world;
  const size_t B = scene.numBodies();
  std::vector<CarvedBody> carved(B);
  std::vector<bool> changed(B, false);
  std::vector<CarveEvent> events;
  for (const auto& [b, mask] : masks) {
    if (b >= B) throw std::out_of_range("carve: body " + std::to_string(b) + " of " + std::to_string(B));
    CarvedBody c = carveBody(carveInput(scene, b), mask);
    if (c.removedVoxels == 0) continue;
    CarveEvent e;
    e.body = b, e.removedVoxels = c.removedVoxels, e.removedVolume = c.removedVolume, e.removedMass = c.removedMass;
    e.removedMomentum = c.removedMomentum, e.removedKineticEnergy = c.removedKineticEnergy;
    e.newVertices = c.newVertices, e.vertices = c.layout.numVertices(), e.elements = c.layout.numElements();
    events.push_back(e);
    carved[b] = std::move(c), changed[b] = true;
  }
  // A new vertex interpolated inside a manipulator (a coarse cell the tool had dented: its
  // trilinear map does not follow the dent) goes to the manipulator's surface, as the contact
  // would have put it; surviving vertices are left as they are.
  for (size_t b = 0; b < B; ++b)
    for (size_t v = 0; changed[b] && v < carved[b].positions.size(); ++v) {
      if (carved[b].fromVertex[v] != Layout::kNoVertex) continue;
      for (const Manipulator& m : world.manipulators()) {
        Vec3 normal;
        const Real d = m.signedDistance(carved[b].positions[v], &normal);
        if (d < 0) carved[b].positions[v] -= d * normal;
      }
    }
  if (events.empty()) return events;
  // The new state, body by body: the carved bodies' from their event, the others' as they were.
  const State& old = world.state();
  State state;
  state.time = old.time;
  for (size_t b = 0; b < B; ++b) {
    if (changed[b]) {
      const CarvedBody& c = carved[b];
      state.positions.insert(state.positions.end(), c.positions.begin(), c.positions.end());
      state.velocities.insert(state.velocities.end(), c.velocities.begin(), c.velocities.end());
      state.rotations.insert(state.rotations.end(), c.rotations.begin(), c.rotations.end());
      continue;
    }
    const BodyRange& r = scene.range(b);
    state.positions.insert(state.positions.end(), old.positions.begin() + r.vertexBegin,
                           old.positions.begin() + r.vertexEnd);
    state.velocities.insert(state.velocities.end(), old.velocities.begin() + r.vertexBegin,
                            old.velocities.begin() + r.vertexEnd);
    state.rotations.insert(state.rotations.end(), old.rotations.begin() + r.elementBegin,
                           old.rotations.begin() + r.elementEnd);
  }
  for (size_t b = 0; b < B; ++b) {
    if (!changed[b]) continue;
    BuiltBody& body = scene.bodies[b];
    body.volume = std::move(carved[b].volume), body.layout = std::move(carved[b].layout);
    body.model = std::move(carved[b].model);
    body.embedded.reset(), body.sourceMesh.reset();  // its vertex ids are gone: drawn by the voxel surface
  }
  std::vector<std::shared_ptr<const RestModel>> models;
  for (const BuiltBody& body : scene.bodies) models.push_back(body.model);
  auto model = B == 1 ? models[0] : std::make_shared<const RestModel>(combineRestModels(models));
  std::vector<ContactBody> contactBodies;
  if (world.bodyContacts()) {
    std::vector<const Layout*> layouts;
    std::vector<const VoxelVolume*> volumes;
    for (const BuiltBody& body : scene.bodies) layouts.push_back(&body.layout), volumes.push_back(&body.volume);
    contactBodies = buildContactBodies(*model, layouts, volumes);
  }
  world.replaceModel(std::move(model), std::move(state), std::move(contactBodies));
  for (const CarveEvent& e : events)
    world.recordRemoval(e.body, RemovedMaterial{e.removedVoxels, e.removedVolume, e.removedMass, e.removedMomentum});
  return events;
}

}  // namespace

CarveInput carveInput(const BuiltScene& scene, size_t body) {
  const BuiltBody& b = scene.bodies.at(body);
  const BodyRange& r = scene.range(body);
  const State& s = scene.world->state();
  CarveInput in;
  in.volume = &b.volume, in.layout = &b.layout, in.model = b.model.get();
  in.positions = s.positions.data() + r.vertexBegin, in.velocities = s.velocities.data() + r.vertexBegin;
  in.rotations = s.rotations.data() + r.elementBegin;
  return in;
}

CarveEvent carveSceneBody(BuiltScene& scene, size_t body, const std::vector<uint8_t>& remove) {
  std::vector<CarveEvent> e = carveBodies(scene, {{body, remove}});
  if (!e.empty()) return e[0];
  CarveEvent none;
  none.body = body;
  return none;
}

// Every body's voxels of `toolVoxels(input, reach [m], &count)`: one event per body that loses any.
template <class ToolVoxels>
std::vector<CarveEvent> carveSceneTool(BuiltScene& scene, Real reachVoxels, ToolVoxels&& toolVoxels) {
  std::vector<std::pair<size_t, std::vector<uint8_t>>> masks;
  for (size_t b = 0; b < scene.numBodies(); ++b) {
    size_t n = 0;
    std::vector<uint8_t> mask = toolVoxels(carveInput(scene, b), reachVoxels * scene.bodies[b].volume.voxelSize(), &n);
    if (n) masks.emplace_back(b, std::move(mask));
  }
  return carveBodies(scene, masks);
}

std::vector<CarveEvent> carveSceneSweep(BuiltScene& scene, const Vec3& from, const Vec3& to, Real radius,
                                        Real reachVoxels) {
  return carveSceneTool(scene, reachVoxels, [&](const CarveInput& in, Real reach, size_t* n) {
    return voxelsInCapsule(in, from, to, radius + reach, n);
  });
}

std::vector<CarveEvent> carveSceneCylinderSweep(BuiltScene& scene, const Vec3& from, const Vec3& to, const Vec3& axis,
                                                Real radius, Real halfLength, Real reachVoxels) {
  return carveSceneTool(scene, reachVoxels, [&](const CarveInput& in, Real reach, size_t* n) {
    return voxelsInCylinder(in, from, to, axis, radius + reach, halfLength + reach, n);
  });
}

std::vector<CarveEvent> carveWithManipulators(BuiltScene& scene, std::vector<Vec3>& previous) {
  const std::vector<Manipulator>& tools = scene.world->manipulators();
  if (previous.size() != tools.size()) {  // the first call: no sweep yet, the centres now
    previous.clear();
    for (const Manipulator& m : tools) previous.push_back(m.position);
  }
  std::vector<CarveEvent> events;
  for (size_t i = 0; i < tools.size(); ++i) {
    const Manipulator& m = scene.world->manipulators()[i];  // the world may have been made again
    const Vec3 now = m.position, from = previous[i];
    previous[i] = now;
    if (!m.settings.carve) continue;
    std::vector<CarveEvent> e;
    if (m.settings.shape == ManipulatorShape::Sphere)
      e = carveSceneSweep(scene, from, now, m.settings.radius, 1.0);
    else if (m.settings.shape == ManipulatorShape::Cylinder)
      e = carveSceneCylinderSweep(scene, from, now, m.settings.axis, m.settings.radius, m.settings.halfLength, 1.0);
    events.insert(events.end(), e.begin(), e.end());
  }
  return events;
}

}  // namespace gradel
