// Moving a manipulator with the pointer (sec. 3.5's "moved by mouse"), shared by gradel-view and
// the web page: pick the manipulator under the cursor, drag it in the plane through the grab
// point facing the camera (or towards / away from the camera), and feed the motion to the world
// a fraction per step with the velocity of the motion (the contacts use it for the bounce).
// GL-free: only the camera and the world.
#pragma once

#include <optional>

#include "gradel/render/camera.h"
#include "gradel/scene.h"
#include "gradel/world.h"

namespace gradel::render {

/// A manipulator held by the pointer.
struct ManipulatorDrag {
  size_t index;
  Vec3 from, to;    ///< [m] manipulator centre at the start of this frame / wanted now
  Vec3 planePoint;  ///< [m] where the drag plane passes
  Vec3 grabOffset;  ///< [m] grab point minus centre
};

/// The manipulator under the pointer (x, y) [pixels]: nearest hit of its bounding sphere (a
/// cylinder's: radius and half length), or, in a flat (2D) view, of its disc.
std::optional<size_t> pickManipulator(const Camera& camera, const World& world, double x, double y, int width,
                                      int height);
/// Grabs manipulator i at the pointer (x, y); a scripted manipulator becomes the user's (its path
/// is cleared).
ManipulatorDrag grabManipulator(const Camera& camera, World& world, size_t i, double x, double y, int width,
                                int height);
/// The pointer moved to (x, y): the wanted centre follows in the drag plane (unchanged when the
/// plane is seen edge-on).
void dragInPlane(const Camera& camera, ManipulatorDrag& drag, double x, double y, int width, int height);
/// Moves the wanted centre (and the drag plane) `metres` towards the camera.
void dragInDepth(const Camera& camera, ManipulatorDrag& drag, Real metres);
/// [m] per pixel at the camera's target, for depth moves by pointer or wheel.
Real pixelSize(const Camera& camera, int height);
/// Poses the dragged manipulator a `fraction` of the way through this frame's motion, with the
/// velocity of that motion over `frameSimSeconds`.
void feedDrag(World& world, const ManipulatorDrag& drag, double fraction, double frameSimSeconds);
/// Before a rebuild: manipulators the user moved (no path) keep their place as a one-key path.
void keepManipulatorPoses(const World& world, Scene& scene);

}  // namespace gradel::render
