#include "gradel/scene.h"

namespace gradel {

BuiltScene buildScene(const Scene& scene) {
  BuiltScene b;
  ShapeSpec shape = scene.body.shape;
  shape.dim = scene.dim;
  b.volume = rasterize(shape);
  b.layout = buildLayout(b.volume, scene.body.layout);
  Vec3 origin = scene.body.position;
  if (scene.dim == 2) origin.z() = 0;
  auto model = std::make_shared<RestModel>(buildRestModel(b.layout, b.volume, scene.body.material, origin));
  b.model = model;
  b.world = std::make_unique<World>(b.model, scene.simulation, scene.domain, scene.manipulators);
  Vec3 v0 = scene.body.velocity;
  if (scene.dim == 2) v0.z() = 0;
  for (Vec3& v : b.world->state().velocities) v = v0;
  return b;
}

}  // namespace gradel
