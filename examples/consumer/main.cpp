// Embedding gradel: a sphere of 8^3 voxels (8 cm across) dropped from 30 cm onto the floor of a
// box, built through the public API (no scene file), simulated for 2 s. Prints where its
// centre of mass is after the fall and exits non-zero when that is not on the floor.
#include <cstdio>

#include <gradel/scene.h>

int main() {
  using namespace gradel;
  Scene scene;
  scene.name = "consumer-drop";
  scene.dim = 3;
  scene.bodies[0].shape = presetShape("sphere", 8, 3, 0.01);  // [m] voxel size
  scene.bodies[0].position = Vec3(-0.04, 0.30, -0.04);        // lattice origin: the sphere's centre at y = 0.34 m
  scene.bodies[0].material.youngsModulus = 1e5;               // [Pa]
  scene.bodies[0].material.density = 1000;                    // [kg/m^3]
  scene.simulation.damping = 4.0;                        // [1/s], as scenes/drop.json
  scene.domain.enabled = true;
  scene.domain.min = Vec3(-0.3, 0.0, -0.3);
  scene.domain.max = Vec3(0.3, 1.0, 0.3);
  scene.domain.restitution = 0.2;
  scene.domain.friction = 0.3;

  BuiltScene built = buildScene(scene);
  World& world = *built.world;
  const RestModel& model = world.model();
  // Mass-weighted mean of positions (or velocities).
  auto centreOfMass = [&](const std::vector<Vec3>& x) {
    Vec3 c = Vec3::Zero();
    Real m = 0;
    for (size_t i = 0; i < model.numVertices(); ++i) {
      c += model.mass[i] * x[i];
      m += model.mass[i];
    }
    return Vec3(c / m);
  };

  const Vec3 start = centreOfMass(world.state().positions);
  world.advanceTo(2.0);
  const Vec3 end = centreOfMass(world.state().positions);
  const Real speed = centreOfMass(world.state().velocities).norm();
  std::printf("%zu elements, %zu vertices, dt = %.3g s, %.2f s simulated\n", model.numElements(), model.numVertices(),
              world.dt(), world.time());
  std::printf("centre of mass: y %.4f m -> %.4f m, moving at %.4f m/s\n", start.y(), end.y(), speed);

  // Resting on the floor: the centre about one radius (4 cm) up, squashed a little, and still.
  const bool onFloor = end.y() > 0.025 && end.y() < 0.05 && speed < 0.05;
  std::printf("%s: the sphere %s\n", onFloor ? "ok" : "FAILED",
              onFloor ? "fell and lies on the floor" : "is not on the floor");
  return onFloor ? 0 : 1;
}
