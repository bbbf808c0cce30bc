#include "gradel/shared/scene_presets.h"

#include <cmath>

namespace gradel {

Scene paperBenchScene(const std::string& shape, int size, LayoutKind layout, int threads) {
  Scene s;
  s.name = "paper-" + shape + std::to_string(size) + "-" + layoutKindName(layout);
  s.dim = 3;
  s.bodies[0].shape = presetShape(shape, size, 3, 1.0);
  s.bodies[0].layout = layout;
  s.bodies[0].material.scaling = Scaling::Paper;
  s.bodies[0].material.paperK = 10000;
  s.bodies[0].material.density = 1.0;
  s.simulation.dt = 0;
  s.simulation.dtFraction = 0.1;
  s.simulation.dtPeriod = PeriodRule::Element;
  s.simulation.gravity = Vec3::Zero();
  s.simulation.damping = 0;
  s.simulation.threads = threads;
  return s;
}

void preparePaperBench(World& world) {
  auto& x = world.state().positions;
  Vec3 c = Vec3::Zero();
  for (const Vec3& p : x) c += p;
  c /= Real(x.size());
  Mat3 eps = Mat3::Identity();
  eps(0, 0) += 0.03, eps(1, 1) -= 0.015, eps(2, 2) += 0.015, eps(0, 1) = 0.015, eps(1, 2) = 0.015;
  for (Vec3& p : x) p = c + eps * (p - c);
}

Scene realBenchScene(int size, Real youngsModulus, LayoutKind layout, int threads) {
  constexpr Real kDiameter = 0.32;  // [m]
  const Real h = kDiameter / size;
  Scene s;
  s.name = "real-sphere" + std::to_string(size) + "-E" + std::to_string(int(std::lround(std::log10(youngsModulus)))) +
           "-" + layoutKindName(layout);
  s.dim = 3;
  s.bodies[0].shape = presetShape("sphere", size, 3, h);
  s.bodies[0].layout = layout;
  s.bodies[0].material.scaling = Scaling::Consistent;
  s.bodies[0].material.youngsModulus = youngsModulus;
  s.bodies[0].material.density = 1000;
  s.bodies[0].position = Vec3(-0.5 * kDiameter, 1e-4, -0.5 * kDiameter);  // just above the floor
  s.simulation.damping = 1.0;
  s.simulation.gravity = Vec3(0, -9.81, 0);
  s.simulation.threads = threads;
  s.domain.enabled = true;
  s.domain.min = Vec3(-0.4, 0, -0.4), s.domain.max = Vec3(0.4, 1.0, 0.4);
  s.domain.restitution = 0.3, s.domain.friction = 0.3;
  ManipulatorSettings press;
  press.shape = ManipulatorShape::Sphere;
  press.radius = 0.06;
  press.restitution = 0.5, press.friction = 0.2;
  const Real top = 1e-4 + kDiameter + press.radius;  // touching the top of the body
  press.path.keys = {{0.0, Vec3(0, top, 0), std::nullopt}, {0.05, Vec3(0, top - 0.05 * kDiameter, 0), std::nullopt}};
  s.manipulators.push_back(press);
  PinSettings pin;  // a patch of the left side, around the equator
  pin.min = Vec3(-0.5 * kDiameter - 1, 0.5 * kDiameter - 0.1 * kDiameter, -0.1 * kDiameter);
  pin.max = Vec3(-0.5 * kDiameter + 1.5 * h, 0.5 * kDiameter + 0.1 * kDiameter, 0.1 * kDiameter);
  s.pins.push_back(pin);
  s.output.frameInterval = 1.0 / 60.0;
  return s;
}

Scene contactBenchScene(int size, int threads) {
  Scene s;
  s.name = "two-spheres" + std::to_string(size);
  s.dim = 3;
  s.bodies.resize(2);
  for (size_t i = 0; i < 2; ++i) {
    BodySettings& b = s.bodies[i];
    b.name = i == 0 ? "left" : "right";
    b.shape = presetShape("sphere", size, 3, 0.01);
    b.position = Vec3(i == 0 ? -size * 0.01 - 0.0005 : 0.0005, 0, 0);  // 1 mm apart
    b.velocity = Vec3(i == 0 ? 0.5 : -0.5, 0, 0);
  }
  s.simulation.damping = 0;
  s.simulation.gravity = Vec3::Zero();
  s.simulation.threads = threads;
  s.bodyContact.restitution = 0.5, s.bodyContact.friction = 0.2;
  return s;
}

}  // namespace gradel
