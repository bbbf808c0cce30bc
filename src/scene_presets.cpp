#include "gradel/scene_presets.h"

namespace gradel {

Scene paperBenchScene(const std::string& shape, int size, LayoutKind layout, int threads) {
  Scene s;
  s.name = "paper-" + shape + std::to_string(size) + "-" + layoutKindName(layout);
  s.dim = 3;
  s.body.shape = presetShape(shape, size, 3, 1.0);
  s.body.layout = layout;
  s.body.material.scaling = Scaling::Paper;
  s.body.material.paperK = 10000;
  s.body.material.density = 1.0;
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

}  // namespace gradel
