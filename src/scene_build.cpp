#include <algorithm>
#include <cmath>
#include <cstdio>

#include "gradel/bodies.h"
#include "gradel/scene.h"
#include "gradel/slow_stage.h"
#include "plane.h"

namespace gradel {

namespace {

constexpr Real kMinVoxelMass = 1e-200;  // [kg]

// One body: volume, layout, rest model and embedded source mesh.
void buildBody(const BodySettings& settings, int dim, const SizeLimits& limits, BuiltBody& b) {
  b.name = settings.name;
  const std::string label = "body" + (settings.name.empty() ? std::string() : " '" + settings.name + "'");
  TriangleMesh latticeMesh;  // a mesh source's mesh, in lattice units
  if (settings.source) {
    SlowStage stage(label + ": reading " + settings.source->describe());
    b.volume = settings.source->loadWithMesh(&latticeMesh);
    if (b.volume.dim() != dim)
      throw InputError(settings.source->describe() + ": a " + std::to_string(b.volume.dim()) + "D volume in a " +
                       std::to_string(dim) + "D scene");
  } else {
    ShapeSpec shape = settings.shape;
    shape.dim = dim;
    const bool labelled =
        std::any_of(shape.primitives.begin(), shape.primitives.end(), [](const Primitive& p) { return p.label != 1; });
    checkVolumeSize(shape.dims, shape.dim, limits, settings.sizeKey, labelled);
    SlowStage stage(label + ": voxelising the shape");
    b.volume = rasterize(shape);
  }
  checkLayoutSize(b.volume, settings.layout, limits, settings.sizeKey);
  // A voxel's mass must be a normal number: density x voxel_size^dim below it underflows (and
  // 1 / mass overflows).
  {
    const Real h = b.volume.voxelSize();
    auto check = [&](Real density, const std::string& key) {
      const Real voxelMass = density * std::pow(h, dim);
      if (!(voxelMass >= kMinVoxelMass) || !std::isfinite(voxelMass)) {
        char buf[320];
        std::snprintf(buf, sizeof buf,
                      "%s x voxel_size^%d = %.3g kg per voxel (density %.3g kg/m^3, voxel_size %.3g m) is out of range "
                      "(expected %.0e to 1e300 kg: a mass that small underflows)",
                      key.c_str(), dim, voxelMass, density, h, kMinVoxelMass);
        throw InputError(settings.name + ": " + buf);
      }
    };
    check(settings.material.density, "material.density");
    for (const auto& r : settings.material.regions) check(r.density, "material.regions.density");
  }
  {
    SlowStage stage(label + ": building the " + layoutKindName(settings.layout) + " layout of " +
                    std::to_string(b.volume.countFilled()) + " voxels");
    b.layout = buildLayout(b.volume, settings.layout);
  }
  SlowStage stage(label + ": building the rest model of " + std::to_string(b.layout.numElements()) + " elements");
  std::shared_ptr<RestModel> model;
  try {
    model = std::make_shared<RestModel>(buildRestModel(b.layout, b.volume, settings.material, settings.position));
  } catch (const InputError& e) {
    // A label of the volume without a material: name the volume file and the scene key.
    if (e.field() != "regions") throw;
    throw e.at(settings.source ? settings.source->describe() : settings.name, "material.");
  }
  b.model = model;
  const Vec3& origin = model->origin;
  if (!latticeMesh.triangles.empty() && dim == 3) {
    // restPositions = origin + lattice * h (model.h): the mesh goes exactly where it was voxelised.
    TriangleMesh rest = std::move(latticeMesh);
    for (Vec3& p : rest.vertices) p = origin + model->voxelSize * p;
    try {
      b.embedded = embedMesh(rest, b.layout, *model);
    } catch (const InputError& e) {
      throw e.at(settings.source->describe());
    }
    b.sourceMesh = std::move(rest);
  }
}

}  // namespace

BuiltScene buildScene(const Scene& given, const SizeLimits& limits) {
  if (given.bodies.empty()) throw InputError(given.name + ": no body (expected \"body\" or \"bodies\")");
  Scene scene = given;
  normalizeFor2D(scene);  // a 2D scene into its plane, once (plane.h)
  BuiltScene b;
  b.bodies.resize(scene.bodies.size());
  // The memory limit holds all bodies: each body is checked against what the ones before leave.
  const uint64_t memory = limits.maxBytes ? limits.maxBytes : defaultMemoryLimit();
  uint64_t used = 0;
  std::vector<std::shared_ptr<const RestModel>> models;
  for (size_t i = 0; i < scene.bodies.size(); ++i) {
    SizeLimits left = limits;
    left.maxBytes = std::max<uint64_t>(1, memory > used ? memory - used : 0);
    BuiltBody& body = b.bodies[i];
    try {
      buildBody(scene.bodies[i], scene.dim, left, body);
    } catch (const InputError& e) {
      if (i == 0 || used == 0) throw;
      throw InputError(
          e.file(), e.field(),
          e.detail() + "; the bodies before it take about " + formatBytes(used) + " of " + formatBytes(memory));
    }
    const Layout& l = body.layout;
    used += estimateModelBytes({l.numElements(), l.numVertices(), l.numPairs()}, scene.dim);
    models.push_back(body.model);
  }
  SlowStage stage("preparing the world: element stages, pins, contact surfaces and start overlaps");
  auto worldModel = models.size() == 1 ? models[0] : std::make_shared<const RestModel>(combineRestModels(models));
  WorldSettings settings;
  settings.simulation = scene.simulation;
  settings.domain = scene.domain;
  settings.manipulators = scene.manipulators;
  settings.pins = scene.pins;
  loadPinMasks(settings.pins);  // the mask files, read here once (the World reads no file)
  settings.bodyContact = scene.bodyContact;
  for (const BodySettings& body : scene.bodies) settings.bodyVelocities.push_back(body.velocity);
  std::vector<ContactBody> contactBodies;
  if (scene.dim == 3 && (scene.bodies.size() > 1 || scene.bodyContact.selfContact)) {
    std::vector<const Layout*> layouts;
    std::vector<const VoxelVolume*> volumes;
    for (const BuiltBody& body : b.bodies) layouts.push_back(&body.layout), volumes.push_back(&body.volume);
    contactBodies = buildContactBodies(*worldModel, layouts, volumes);
  }
  b.world = std::make_unique<World>(std::move(worldModel), std::move(settings), std::move(contactBodies));
  return b;
}

}  // namespace gradel
