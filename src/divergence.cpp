#include "gradel/divergence.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace gradel {

double allowedEnergy(const EnergyBudget& b, const DivergenceSettings& s, const Metrics& now) {
  if (b.unbounded) return std::numeric_limits<double>::infinity();
  const double gravityDrop = std::max(0.0, b.initial.gravityEnergy - now.gravityEnergy);
  const double hit = 0.5 * b.mass * (2 * b.drivenSpeed) * (2 * b.drivenSpeed);
  const double slack = 0.5 * b.mass * s.slackSpeed * s.slackSpeed;
  return s.energyFactor *
         (std::max(0.0, b.initial.kineticEnergy) + std::max(0.0, b.initial.elasticEnergy) + gravityDrop + hit + slack);
}

double maxPathSpeed(const Path& path, double duration) {
  double speed = 0;
  const auto sample = [&](double t) {
    const double v = path.velocity(t).norm();
    if (std::isfinite(v)) speed = std::max(speed, v);
  };
  for (size_t k = 0; k < path.keys.size(); ++k) {
    const double t0 = path.keys[k].time;
    sample(t0);
    if (path.keys[k].velocity) speed = std::max(speed, double(path.keys[k].velocity->norm()));
    if (k + 1 < path.keys.size()) {
      const double t1 = path.keys[k + 1].time;
      for (int i = 1; i < 64; ++i) sample(t0 + (t1 - t0) * i / 64.0);
    }
  }
  if (!path.keys.empty() && path.keys.back().time < duration) sample(duration);
  return speed;
}

EnergyBudget energyBudget(const World& world, double duration) {
  EnergyBudget b;
  b.initial = world.metrics();
  for (Real m : world.model().mass) b.mass += m;
  for (const Manipulator& m : world.manipulators())
    b.drivenSpeed = std::max(b.drivenSpeed, maxPathSpeed(m.settings.path, duration));
  for (const PinSettings& p : world.pins())
    for (const Keyframe& k : p.path.keys)
      if (k.position.norm() > 0 || (k.velocity && k.velocity->norm() > 0)) b.unbounded = true;
  return b;
}

std::optional<std::string> DivergenceGuard::check(const Metrics& m, const std::string& cause) {
  char buf[640];
  const double energy = m.kineticEnergy + m.elasticEnergy;
  const double allowed = allowedEnergy(budget_, settings_, m);
  if (!std::isfinite(energy) || energy > allowed) {
    std::snprintf(buf, sizeof buf,
                  "simulation diverged at t = %.4g s: kinetic + elastic energy %.3g J is over %.3g J, %g x what the "
                  "initial state (%.3g J), gravity and manipulators (up to %.3g m/s) can have supplied "
                  "(min element det %.3g); %s",
                  m.time, energy, allowed, settings_.energyFactor,
                  budget_.initial.kineticEnergy + budget_.initial.elasticEnergy, budget_.drivenSpeed, m.minElementDet,
                  cause.c_str());
    return std::string(buf);
  }
  if (m.minElementDet < 0) {
    if (invertedFrames_++ == 0) invertedSince_ = m.time;
    if (invertedFrames_ >= settings_.inversionFrames && m.time - invertedSince_ >= settings_.inversionSeconds) {
      std::snprintf(buf, sizeof buf,
                    "simulation diverged: elements inverted (min element det %.3g) in %d frames running, from t = %.4g "
                    "to %.4g s (kinetic + elastic energy %.3g J); %s",
                    m.minElementDet, invertedFrames_, invertedSince_, m.time, energy, cause.c_str());
      return std::string(buf);
    }
  } else {
    invertedFrames_ = 0;
  }
  return std::nullopt;
}

}  // namespace gradel
