// Carving in a built scene: carveBody per body, then the world made again once (carve_scene.h).
#include "gradel/carve_scene.h"

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <stdexcept>
#include <utility>
#include <vector>

#include "gradel/bodies.h"
#include "gradel/contact_surface.h"
#include "gradel/pieces.h"
#include "gradel/pins.h"

namespace gradel {

namespace {

// A new piece's name: the body's name, "-", the smallest number from 2 no body has taken (a
// scene's names are file names: at most 100 of A-Z a-z 0-9 _ - ., so the name is cut to fit).
std::string pieceName(const BuiltScene& scene, const std::string& name) {
  for (size_t n = 2;; ++n) {
    const std::string suffix = "-" + std::to_string(n);
    const std::string candidate = name.substr(0, 100 - suffix.size()) + suffix;
    bool taken = false;
    for (const BuiltBody& b : scene.bodies) taken = taken || b.name == candidate;
    if (!taken) return candidate;
  }
}

// The pins after bodies fell apart: a pin of such a body is copied to each of its pieces
// (pieceBodies[b]: scene indices) whose vertices it selects, in place; one that selects none of
// them stays on the body (World::setPins then says it holds no vertex, as when carving took all
// its vertices).
std::vector<PinSettings> pinsOverPieces(const BuiltScene& scene, const std::vector<PinSettings>& pins,
                                        const std::vector<std::vector<size_t>>& pieceBodies) {
  std::vector<PinSettings> out;
  for (const PinSettings& pin : pins) {
    if (pin.body >= pieceBodies.size() || pieceBodies[pin.body].size() < 2) {
      out.push_back(pin);
      continue;
    }
    const size_t before = out.size();
    for (size_t s : pieceBodies[pin.body]) {
      PinSettings alone = pin;
      alone.body = 0;
      try {
        selectPins({alone}, scene.bodies[s].model->restPositions);
      } catch (const InputError&) {
        continue;  // holds no vertex of this piece
      }
      PinSettings copy = pin;
      copy.body = uint32_t(s);
      out.push_back(std::move(copy));
    }
    if (out.size() == before) out.push_back(pin);
  }
  return out;
}

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
  // Pieces (pieces.h): a carved body whose material fell apart becomes one body per piece, the
  // largest in its place (its name and index), the others appended after every body, in order.
  std::vector<std::vector<BodyPiece>> pieces(B);
  for (size_t b = 0; b < B; ++b) {
    if (!changed[b]) continue;
    const CarvedBody& c = carved[b];
    CarveInput in;
    in.volume = &c.volume, in.layout = &c.layout, in.model = c.model.get();
    in.positions = c.positions.data(), in.velocities = c.velocities.data(), in.rotations = c.rotations.data();
    pieces[b] = splitBody(in);
  }
  // The new state, body by body in the new bodies' order (the carved bodies' from their event or
  // their largest piece, the others' as they were, then the other pieces), and per new vertex its
  // id in the world's model (UINT32_MAX: new): the operator rule's estimate starts from the last
  // one's fastest mode (stability_warm.h).
  const State& old = world.state();
  State state;
  state.time = old.time;
  std::vector<uint32_t> fromVertex;
  // Carved body b, whole (piece null) or one of its pieces.
  auto appendCarved = [&](size_t b, const BodyPiece* piece) {
    const CarvedBody& c = carved[b];
    const std::vector<Vec3>& x = piece ? piece->positions : c.positions;
    const std::vector<Vec3>& v = piece ? piece->velocities : c.velocities;
    const std::vector<Quat>& q = piece ? piece->rotations : c.rotations;
    state.positions.insert(state.positions.end(), x.begin(), x.end());
    state.velocities.insert(state.velocities.end(), v.begin(), v.end());
    state.rotations.insert(state.rotations.end(), q.begin(), q.end());
    const uint32_t begin = uint32_t(scene.range(b).vertexBegin);
    for (size_t i = 0; i < x.size(); ++i) {
      uint32_t from = piece ? piece->fromVertex[i] : uint32_t(i);  // into the carved body, then the world
      if (from != Layout::kNoVertex) from = c.fromVertex[from];
      fromVertex.push_back(from == Layout::kNoVertex ? from : begin + from);
    }
  };
  for (size_t b = 0; b < B; ++b) {
    if (changed[b]) {
      appendCarved(b, pieces[b].empty() ? nullptr : &pieces[b][0]);
      continue;
    }
    const BodyRange& r = scene.range(b);
    state.positions.insert(state.positions.end(), old.positions.begin() + r.vertexBegin,
                           old.positions.begin() + r.vertexEnd);
    state.velocities.insert(state.velocities.end(), old.velocities.begin() + r.vertexBegin,
                            old.velocities.begin() + r.vertexEnd);
    state.rotations.insert(state.rotations.end(), old.rotations.begin() + r.elementBegin,
                           old.rotations.begin() + r.elementEnd);
    for (size_t v = r.vertexBegin; v < r.vertexEnd; ++v) fromVertex.push_back(uint32_t(v));
  }
  for (size_t b = 0; b < B; ++b)
    for (size_t k = 1; k < pieces[b].size(); ++k) appendCarved(b, &pieces[b][k]);
  // The pins of a body that fell apart hold the pieces their box or mask selects (one pin each).
  const std::vector<PinSettings> oldPins = world.pins();
  bool split = false;
  for (size_t b = 0; b < B; ++b) split = split || !pieces[b].empty();
  std::vector<std::vector<size_t>> pieceBodies(B);
  for (size_t b = 0; b < B; ++b) pieceBodies[b].push_back(b);
  for (size_t b = 0, next = B; b < B; ++b)
    for (size_t k = 1; k < pieces[b].size(); ++k) pieceBodies[b].push_back(next++);
  // The carved bodies as they were, put back if the new world cannot be made (a pin that holds
  // no vertex any more), so that the scene and its world stay each other's. A carved body keeps
  // its name only: its embedded mesh's vertex ids are gone (drawn by its voxel surface from now on).
  struct Restore {
    BuiltScene& scene;
    size_t bodies;
    std::vector<BuiltBody> before;
    bool done = false;
    ~Restore() {
      if (done) return;
      scene.bodies.resize(bodies);
      for (size_t b = 0; b < bodies; ++b)
        if (before[b].model) scene.bodies[b] = std::move(before[b]);
    }
  } restore{scene, B, std::vector<BuiltBody>(B)};
  for (size_t b = 0; b < B; ++b) {
    if (!changed[b]) continue;
    restore.before[b] = std::move(scene.bodies[b]);
    scene.bodies[b] = BuiltBody{};
    scene.bodies[b].name = restore.before[b].name;
  }
  for (size_t b = 0; b < B; ++b) {
    if (!changed[b]) continue;
    BuiltBody& body = scene.bodies[b];
    if (pieces[b].empty()) {
      body.volume = std::move(carved[b].volume), body.layout = std::move(carved[b].layout);
      body.model = std::move(carved[b].model);
      continue;
    }
    for (size_t k = 1; k < pieces[b].size(); ++k) {
      BuiltBody p;
      p.name = pieceName(scene, body.name);
      p.volume = std::move(pieces[b][k].volume), p.layout = std::move(pieces[b][k].layout);
      p.model = std::move(pieces[b][k].model);
      scene.bodies.push_back(std::move(p));
    }
    BuiltBody& first = scene.bodies[b];  // push_back may have moved it
    first.volume = std::move(pieces[b][0].volume), first.layout = std::move(pieces[b][0].layout);
    first.model = std::move(pieces[b][0].model);
  }
  std::vector<PinSettings> pins;
  if (split) pins = pinsOverPieces(scene, oldPins, pieceBodies);
  std::vector<std::shared_ptr<const RestModel>> models;
  for (const BuiltBody& body : scene.bodies) models.push_back(body.model);
  auto model =
      models.size() == 1 ? models[0] : std::make_shared<const RestModel>(combineRestModels(models));
  // Contact between the bodies as a scene has it (scene.h): in 3D when there are several bodies
  // (the pieces of a body collide like any two bodies), or when the world had it (self_contact).
  std::vector<ContactBody> contactBodies;
  if (world.bodyContacts() || (model->dim == 3 && models.size() > 1)) {
    std::vector<const Layout*> layouts;
    std::vector<const VoxelVolume*> volumes;
    for (const BuiltBody& body : scene.bodies) layouts.push_back(&body.layout), volumes.push_back(&body.volume);
    contactBodies = buildContactBodies(*model, layouts, volumes);
  }
  world.replaceModel(std::move(model), std::move(state), std::move(contactBodies), split ? &pins : nullptr, &fromVertex);
  restore.done = true;
  for (CarveEvent& e : events) {
    world.recordRemoval(e.body, RemovedMaterial{e.removedVoxels, e.removedVolume, e.removedMass, e.removedMomentum});
    e.pieces = pieceBodies[e.body];
    e.vertices = 0, e.elements = 0;
    for (size_t s : e.pieces) e.vertices += scene.bodies[s].layout.numVertices(), e.elements += scene.bodies[s].layout.numElements();
  }
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

// Keeps the voxels of `mask` whose label is one of `labels` (ascending; empty: all); returns how
// many are left.
size_t keepLabels(const VoxelVolume& volume, const std::vector<uint16_t>& labels, std::vector<uint8_t>& mask) {
  size_t n = 0;
  const std::vector<uint16_t>& of = volume.labels();  // empty for a binary volume: every voxel label 1
  for (size_t q = 0; q < mask.size(); ++q) {
    if (!mask[q]) continue;
    const uint16_t label = of.empty() ? uint16_t(1) : of[q];
    if (labels.empty() || std::binary_search(labels.begin(), labels.end(), label))
      ++n;
    else
      mask[q] = 0;
  }
  return n;
}

// Every body's voxels of `toolVoxels(input, reach [m], &count)` with one of `labels` (empty: any):
// one event per body that loses any.
template <class ToolVoxels>
std::vector<CarveEvent> carveSceneTool(BuiltScene& scene, Real reachVoxels, const std::vector<uint16_t>& labels,
                                       ToolVoxels&& toolVoxels) {
  std::vector<std::pair<size_t, std::vector<uint8_t>>> masks;
  for (size_t b = 0; b < scene.numBodies(); ++b) {
    size_t n = 0;
    std::vector<uint8_t> mask = toolVoxels(carveInput(scene, b), reachVoxels * scene.bodies[b].volume.voxelSize(), &n);
    if (n && !labels.empty()) n = keepLabels(scene.bodies[b].volume, labels, mask);
    if (n) masks.emplace_back(b, std::move(mask));
  }
  return carveBodies(scene, masks);
}

std::vector<CarveEvent> carveSceneSweep(BuiltScene& scene, const Vec3& from, const Vec3& to, Real radius,
                                        Real reachVoxels, const std::vector<uint16_t>& labels) {
  return carveSceneTool(scene, reachVoxels, labels, [&](const CarveInput& in, Real reach, size_t* n) {
    return voxelsInCapsule(in, from, to, radius + reach, n);
  });
}

std::vector<CarveEvent> carveSceneCylinderSweep(BuiltScene& scene, const Vec3& from, const Vec3& to, const Vec3& axis,
                                                Real radius, Real halfLength, Real reachVoxels,
                                                const std::vector<uint16_t>& labels) {
  return carveSceneTool(scene, reachVoxels, labels, [&](const CarveInput& in, Real reach, size_t* n) {
    return voxelsInCylinder(in, from, to, axis, radius + reach, halfLength + reach, n);
  });
}

std::vector<CarveEvent> carveSceneBlade(BuiltScene& scene, const BladeSweep& blade, const std::vector<uint16_t>& labels) {
  return carveSceneTool(scene, 0, labels, [&](const CarveInput& in, Real, size_t* n) {
    if (in.layout->dim != 3) return std::vector<uint8_t>(in.volume->size(), 0);
    return voxelsAlongBlade(in, blade, n);
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
    const std::vector<uint16_t> labels = m.settings.carveLabels;  // a copy: an event makes the world again
    if (m.settings.shape == ManipulatorShape::Sphere)
      e = carveSceneSweep(scene, from, now, m.settings.radius, 1.0, labels);
    else if (m.settings.shape == ManipulatorShape::Cylinder)
      e = carveSceneCylinderSweep(scene, from, now, m.settings.axis, m.settings.radius, m.settings.halfLength, 1.0,
                                  labels);
    else if (m.settings.shape == ManipulatorShape::Blade)
      e = carveSceneBlade(scene,
                          BladeSweep{from, now, m.settings.axis, m.settings.widthAxis, m.settings.halfLength,
                                     m.settings.halfWidth},
                          labels);
    events.insert(events.end(), e.begin(), e.end());
  }
  return events;
}

}  // namespace gradel
