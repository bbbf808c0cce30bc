#include "gradel/render/camera.h"

#include <algorithm>
#include <cmath>

namespace gradel::render {

namespace {
constexpr Real kNear = 0.01;  // [m]
constexpr Real kFar = 50.0;   // [m]
constexpr Real kOrbitRadPerPixel = 0.008;
constexpr Real kPitchLimit = 1.5;  // [rad], just short of straight up / down
}  // namespace

Vec3 Camera::eye() const {
  if (flat) return target + Vec3(0, 0, 10 * std::max(distance, Real(0.1)));
  return target + distance * Vec3(std::cos(pitch) * std::sin(yaw), std::sin(pitch), std::cos(pitch) * std::cos(yaw));
}

Vec3 Camera::right() const {
  if (flat) return Vec3(1, 0, 0);
  return Vec3(std::cos(yaw), 0, -std::sin(yaw));
}

Vec3 Camera::up() const {
  if (flat) return Vec3(0, 1, 0);
  const Vec3 back = (eye() - target).normalized();
  return back.cross(right()).normalized();
}

Mat4f Camera::view() const {
  const Vec3 f = (target - eye()).normalized(), r = right(), u = up(), e = eye();
  Mat4f m = Mat4f::Identity();
  m.block<1, 3>(0, 0) = r.cast<float>().transpose();
  m.block<1, 3>(1, 0) = u.cast<float>().transpose();
  m.block<1, 3>(2, 0) = (-f).cast<float>().transpose();
  m(0, 3) = float(-r.dot(e));
  m(1, 3) = float(-u.dot(e));
  m(2, 3) = float(f.dot(e));
  return m;
}

Mat4f Camera::projection(Real aspect) const {
  Mat4f p = Mat4f::Zero();
  if (flat) {
    const Real h = distance, w = distance * aspect, n = 0.0, fz = 20 * std::max(distance, Real(0.1)) + 1;
    p(0, 0) = float(1 / w);
    p(1, 1) = float(1 / h);
    p(2, 2) = float(-2 / (fz - n));
    p(2, 3) = float(-(fz + n) / (fz - n));
    p(3, 3) = 1;
    return p;
  }
  const Real t = 1 / std::tan(fovY / 2);
  p(0, 0) = float(t / aspect);
  p(1, 1) = float(t);
  p(2, 2) = float(-(kFar + kNear) / (kFar - kNear));
  p(2, 3) = float(-2 * kFar * kNear / (kFar - kNear));
  p(3, 2) = -1;
  return p;
}

Vec3 Camera::project(const Vec3& p, int width, int height) const {
  const Eigen::Vector4f c =
      projection(Real(width) / height) * view() * Eigen::Vector4f(float(p.x()), float(p.y()), float(p.z()), 1);
  const Real x = c.x() / c.w(), y = c.y() / c.w(), z = c.z() / c.w();
  return Vec3((x + 1) / 2 * width, (1 - y) / 2 * height, z);
}

void Camera::ray(Real x, Real y, int width, int height, Vec3* origin, Vec3* direction) const {
  const Real aspect = Real(width) / height;
  const Real nx = 2 * x / width - 1, ny = 1 - 2 * y / height;
  if (flat) {
    *origin = eye() + right() * (nx * distance * aspect) + up() * (ny * distance);
    *direction = Vec3(0, 0, -1);
    return;
  }
  const Real t = std::tan(fovY / 2);
  const Vec3 f = (target - eye()).normalized();
  *origin = eye();
  *direction = (f + right() * (nx * t * aspect) + up() * (ny * t)).normalized();
}

void Camera::orbit(Real dx, Real dy) {
  if (flat) return;
  yaw -= dx * kOrbitRadPerPixel;
  pitch = std::clamp(pitch + dy * kOrbitRadPerPixel, -kPitchLimit, kPitchLimit);
}

void Camera::pan(Real dx, Real dy, int height) {
  // One pixel moves the target by the size of one pixel at the target's depth.
  const Real pixel = flat ? 2 * distance / height : 2 * distance * std::tan(fovY / 2) / height;
  target += (-dx * right() + dy * up()) * pixel;
}

void Camera::zoom(Real steps) { distance = std::clamp(distance * std::pow(0.9, steps), Real(0.01), Real(20)); }

Camera frameBox(const Vec3& lo, const Vec3& hi, bool flat) {
  Camera c;
  c.flat = flat;
  c.target = (lo + hi) / 2;
  const Real radius = std::max((hi - lo).norm() / 2, Real(0.01));
  c.distance = flat ? 1.15 * std::max((hi - lo).y(), (hi - lo).x() * 0.75) / 2 : radius / std::sin(c.fovY / 2) * 1.05;
  if (flat) c.yaw = c.pitch = 0;
  return c;
}

void CameraFollow::update(Camera& camera, const Vec3& lo, const Vec3& hi, bool hold) {
  const Vec3 c = (lo + hi) / 2;
  const Real size = (hi - lo).norm();
  if (!c.allFinite() || !std::isfinite(size)) return;
  if (centre && !hold) {
    camera.target += c - *centre;
    if (size > extent && extent > 0) camera.distance *= size / extent;
  }
  if (!centre || size > extent) extent = size;
  centre = c;
}

}  // namespace gradel::render
