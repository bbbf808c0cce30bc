#include "gradel/render/manipulator_drag.h"

#include <cmath>

namespace gradel::render {
namespace {

Vec3 planeNormal(const Camera& camera) {
  return camera.flat ? Vec3(0, 0, 1) : Vec3((camera.eye() - camera.target).normalized());
}

}  // namespace

std::optional<size_t> pickManipulator(const Camera& camera, const World& world, double x, double y, int width,
                                      int height) {
  Vec3 o, d;
  camera.ray(x, y, width, height, &o, &d);
  std::optional<size_t> best;
  Real bestT = 1e30;
  const auto& ms = world.manipulators();
  for (size_t i = 0; i < ms.size(); ++i) {
    const Vec3 c = ms[i].position;
    Real r = ms[i].settings.radius;
    if (ms[i].settings.shape == ManipulatorShape::Cylinder) r = std::hypot(r, ms[i].settings.halfLength);
    if (ms[i].settings.shape == ManipulatorShape::Blade) r = std::hypot(ms[i].settings.halfLength, ms[i].settings.halfWidth);
    if (camera.flat) {
      const Vec3 q = o - c;
      if (std::hypot(q.x(), q.y()) <= r && q.norm() < bestT) best = i, bestT = q.norm();
      continue;
    }
    const Real b = (c - o).dot(d), h = (c - o).squaredNorm() - b * b;
    if (h <= r * r && b > 0 && b < bestT) best = i, bestT = b;
  }
  return best;
}

ManipulatorDrag grabManipulator(const Camera& camera, World& world, size_t i, double x, double y, int width,
                                int height) {
  Manipulator& m = world.manipulators()[i];
  m.settings.path.keys.clear();
  Vec3 o, d;
  camera.ray(x, y, width, height, &o, &d);
  const Vec3 n = planeNormal(camera);
  const Real t = std::abs(d.dot(n)) < 1e-9 ? 0 : (m.position - o).dot(n) / d.dot(n);
  const Vec3 offset = o + t * d - m.position;  // 2D: World::setManipulatorPose keeps the pose in the plane
  return ManipulatorDrag{i, m.position, m.position, m.position, offset};
}

void dragInPlane(const Camera& camera, ManipulatorDrag& drag, double x, double y, int width, int height) {
  Vec3 o, d;
  camera.ray(x, y, width, height, &o, &d);
  const Vec3 n = planeNormal(camera);
  if (std::abs(d.dot(n)) < 1e-9) return;
  const Real t = (drag.planePoint - o).dot(n) / d.dot(n);
  drag.to = o + t * d - drag.grabOffset;
}

void dragInDepth(const Camera& camera, ManipulatorDrag& drag, Real metres) {
  const Vec3 toward = (camera.eye() - camera.target).normalized();
  drag.to += metres * toward;
  drag.planePoint += metres * toward;
}

Real pixelSize(const Camera& camera, int height) {
  return camera.flat ? 2 * camera.distance / height : 2 * camera.distance * std::tan(camera.fovY / 2) / height;
}

void feedDrag(World& world, const ManipulatorDrag& drag, double fraction, double frameSimSeconds) {
  const Vec3 p = drag.from + fraction * (drag.to - drag.from);
  const Vec3 v = frameSimSeconds > 0 ? Vec3((drag.to - drag.from) / frameSimSeconds) : Vec3::Zero();
  world.setManipulatorPose(drag.index, p, v);
}

void keepManipulatorPoses(const World& world, Scene& scene) {
  const auto& ms = world.manipulators();
  for (size_t i = 0; i < ms.size() && i < scene.manipulators.size(); ++i)
    if (ms[i].settings.path.keys.empty()) scene.manipulators[i].path.keys = {Keyframe{0, ms[i].position, std::nullopt}};
}

}  // namespace gradel::render
