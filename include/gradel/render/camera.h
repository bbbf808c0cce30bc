// The view camera: orbit (yaw, pitch, distance about a target) with a perspective projection in
// 3D; a flat orthographic view of the z = 0 plane in 2D. Pure maths, no OpenGL.
#pragma once

#include <optional>

#include <Eigen/Core>

#include "gradel/types.h"

namespace gradel::render {

using Mat4f = Eigen::Matrix4f;

struct Camera {
  Vec3 target{0, 0, 0};  ///< [m] point orbited and looked at.
  Real yaw = 0.6;        ///< [rad] about +y, 0 = looking along -z.
  Real pitch = 0.35;     ///< [rad] above the horizon.
  Real distance = 0.5;   ///< [m] from the target (3D); half the visible height (2D).
  Real fovY = 0.7;       ///< [rad] vertical field of view (3D).
  bool flat = false;     ///< 2D: orthographic, looking along -z.

  Vec3 eye() const;
  Mat4f view() const;
  Mat4f projection(Real aspect) const;
  /// Pixel (x right, y down) of a world point in a width x height view; z = NDC depth.
  Vec3 project(const Vec3& p, int width, int height) const;
  /// World ray through pixel (x, y): origin and unit direction.
  void ray(Real x, Real y, int width, int height, Vec3* origin, Vec3* direction) const;
  /// The camera's right and up axes in world space (for dragging in the plane facing it).
  Vec3 right() const;
  Vec3 up() const;

  /// Orbit / pan / zoom by mouse deltas in pixels (the viewer's controls).
  void orbit(Real dxPixels, Real dyPixels);
  void pan(Real dxPixels, Real dyPixels, int height);
  void zoom(Real wheelSteps);
};

/// A camera that frames the axis-aligned box [lo, hi] [m] from the default angle.
Camera frameBox(const Vec3& lo, const Vec3& hi, bool flat);

/// A camera that follows the bodies (gradel-view and the web page): each frame the target moves
/// with the centre of the bodies' bounds, so the bodies stay where they were on screen, and the
/// camera steps back as the bounds grow past the largest seen (bodies flying apart), never
/// closer; orbit, pan and zoom stay the user's. reset() after a reframe or a new scene.
struct CameraFollow {
  std::optional<Vec3> centre;  ///< [m] the bounds' centre at the last update.
  Real extent = 0;             ///< [m] the largest bounds diagonal seen.
  /// `hold`: the user is dragging a manipulator (the camera keeps still under the mouse).
  void update(Camera& camera, const Vec3& lo, const Vec3& hi, bool hold);
  void reset() { centre.reset(), extent = 0; }
};

}  // namespace gradel::render
