#include "gradel/scene.h"

#include <algorithm>

namespace gradel {

BuiltScene buildScene(const Scene& scene, const SizeLimits& limits) {
  BuiltScene b;
  TriangleMesh latticeMesh;  // a mesh source's mesh, in lattice units
  if (scene.body.source) {
    b.volume = scene.body.source->loadWithMesh(&latticeMesh);
    if (b.volume.dim() != scene.dim)
      throw InputError(scene.body.source->describe() + ": a " + std::to_string(b.volume.dim()) + "D volume in a " +
                       std::to_string(scene.dim) + "D scene");
  } else {
    ShapeSpec shape = scene.body.shape;
    shape.dim = scene.dim;
    const bool labelled =
        std::any_of(shape.primitives.begin(), shape.primitives.end(), [](const Primitive& p) { return p.label != 1; });
    checkVolumeSize(shape.dims, shape.dim, limits, scene.body.sizeKey, labelled);
    b.volume = rasterize(shape);
  }
  checkLayoutSize(b.volume, scene.body.layout, limits, scene.body.sizeKey);
  b.layout = buildLayout(b.volume, scene.body.layout);
  std::shared_ptr<RestModel> model;
  try {
    model =
        std::make_shared<RestModel>(buildRestModel(b.layout, b.volume, scene.body.material, scene.body.position));
  } catch (const InputError& e) {
    // A label of the volume without a material: name the volume file and the scene key.
    const std::string m = e.what();
    if (m.rfind("regions: ", 0) != 0) throw;
    throw InputError((scene.body.source ? scene.body.source->describe() : std::string("body")) + ": material." + m);
  }
  b.model = model;
  const Vec3& origin = model->origin;
  if (!latticeMesh.triangles.empty() && scene.dim == 3) {
    // restPositions = origin + lattice * h (model.h): the mesh goes exactly where it was voxelised.
    TriangleMesh rest = std::move(latticeMesh);
    for (Vec3& p : rest.vertices) p = origin + model->voxelSize * p;
    try {
      b.embedded = embedMesh(rest, b.layout, *model);
    } catch (const InputError& e) {
      throw InputError(scene.body.source->describe() + ": " + e.what());
    }
    b.sourceMesh = std::move(rest);
  }
  b.world = std::make_unique<World>(b.model, scene.simulation, scene.domain, scene.manipulators);
  if (!scene.pins.empty()) {
    std::vector<PinSettings> pins = scene.pins;
    loadPinMasks(pins);  // the mask files, read here once (World::setPins reads no file)
    b.world->setPins(std::move(pins));
  }
  Vec3 v0 = scene.body.velocity;
  if (scene.dim == 2) v0.z() = 0;
  for (Vec3& v : b.world->state().velocities) v = v0;
  return b;
}

}  // namespace gradel
