// A 2D scene lives in the plane z = 0 (dim 2: the bodies, circles, gravity, walls and pins in
// x-y). Its inputs are put into that plane once, where they enter: a scene by normalizeFor2D
// (buildScene), a World's run-time inputs at its API (the constructor's gravity and initial
// velocities, addManipulator, setManipulatorPose, addExternalForces, setPins, replaceModel's
// state). No kernel or step stage projects: a state, pose and force with z = 0 stay at z = 0
// through every integrator (tests/test_plane.cpp checks it).
#pragma once

#include "gradel/contacts.h"
#include "gradel/types.h"

namespace gradel {

struct Scene;

/// v with z = 0 in 2D (dim 2); v unchanged in 3D.
inline Vec3 projectToPlane(Vec3 v, int dim) {
  if (dim == 2) v.z() = 0;
  return v;
}

/// A path's keyframes (positions and velocities) put into the plane in 2D.
inline void projectToPlane(Path& path, int dim) {
  if (dim != 2) return;
  for (Keyframe& k : path.keys) {
    k.position.z() = 0;
    if (k.velocity) k.velocity->z() = 0;
  }
}

/// A 2D scene put into its plane, once, before it is built: every body's position and velocity,
/// gravity, the manipulators' and pins' paths z = 0; the domain's and pin boxes' z range [-1, 1]
/// (z is unused in 2D; a non-empty range keeps the plane inside). A 3D scene is unchanged.
void normalizeFor2D(Scene& scene);

}  // namespace gradel
