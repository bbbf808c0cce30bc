#include "plane.h"

#include "gradel/scene.h"

namespace gradel {

void normalizeFor2D(Scene& scene) {
  if (scene.dim != 2) return;
  const int dim = scene.dim;
  for (BodySettings& b : scene.bodies) b.position = projectToPlane(b.position, dim), b.velocity = projectToPlane(b.velocity, dim);
  scene.simulation.gravity = projectToPlane(scene.simulation.gravity, dim);
  scene.domain.min.z() = -1, scene.domain.max.z() = 1;
  for (ManipulatorSettings& m : scene.manipulators) projectToPlane(m.path, dim);
  for (PinSettings& p : scene.pins) {
    p.min.z() = -1, p.max.z() = 1;
    projectToPlane(p.path, dim);
    if (p.mask) {
      // The mask is shared (a shared_ptr the reader made): a copy with its origin in the plane.
      auto mask = std::make_shared<PinMask>(*p.mask);
      mask->origin = projectToPlane(mask->origin, dim);
      p.mask = std::move(mask);
    }
  }
}

}  // namespace gradel
