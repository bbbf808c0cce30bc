#include "gradel/divergence.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace gradel {

double suppliedWork(const World& world) { return world.contactWork() + world.externalWork(); }

double allowedEnergy(const EnergyBudget& b, const DivergenceSettings& s, const Metrics& now, double contactWork) {
  if (b.unbounded) return std::numeric_limits<double>::infinity();
  const double gravityDrop = std::max(0.0, b.initial.gravityEnergy - now.gravityEnergy);
  const double hit = 0.5 * b.mass * (2 * b.drivenSpeed) * (2 * b.drivenSpeed);
  const double slack = 0.5 * b.mass * s.slackSpeed * s.slackSpeed;
  const double work = std::isfinite(contactWork) ? std::max(0.0, contactWork) : 0.0;
  return s.energyFactor * (std::max(0.0, b.initial.kineticEnergy) + std::max(0.0, b.initial.elasticEnergy) +
                           gravityDrop + hit + slack + work);
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

DivergenceFacts divergenceFacts(const World& world, double duration) {
  DivergenceFacts f;
  const SimulationSettings& s = world.settings();
  const RestModel& m = world.model();
  f.forwardEuler = s.integrator == IntegratorKind::ForwardEuler;
  f.explicitStep = s.integrator == IntegratorKind::ForwardEuler || s.integrator == IntegratorKind::SymplecticEuler;
  f.dtGiven = s.dt > 0;
  f.dt = world.dt();
  f.dtFraction = s.dtFraction;
  f.period = s.dtPeriod == PeriodRule::Element ? m.smallestPeriod : m.smallestVertexPeriod;
  // Symplectic Euler is stable for omega dt < 2: omega_max of the assembled body where the world
  // estimated it (the operator rule, stability.h), else the stiffest vertex's 2 pi / its period (an
  // upper bound of omega_max: a limit on the safe side).
  const double omega = world.stabilityEstimate().omega;
  if (s.dtPeriod == PeriodRule::Operator && omega > 0) f.period = 2 * M_PI / omega;
  f.stableDt = s.dtPeriod == PeriodRule::Operator && omega > 0 ? 2 / omega : m.smallestVertexPeriod / M_PI;
  for (const Manipulator& k : world.manipulators())
    f.manipulatorSpeed = std::max(f.manipulatorSpeed, maxPathSpeed(k.settings.path, duration));
  for (const Vec3& v : world.state().velocities)
    if (v.allFinite()) f.bodySpeed = std::max(f.bodySpeed, double(v.norm()));
  f.voxelSize = std::numeric_limits<double>::infinity();
  for (const BodyRange& b : m.bodies) f.voxelSize = std::min(f.voxelSize, double(b.voxelSize));
  if (m.bodies.empty()) f.voxelSize = m.voxelSize;
  double lo = std::numeric_limits<double>::infinity(), hi = 0;
  for (const MaterialSettings& mat : m.materials)
    if (mat.youngsModulus > 0) lo = std::min(lo, double(mat.youngsModulus)), hi = std::max(hi, double(mat.youngsModulus));
  if (hi > 0) f.softE = lo, f.stiffE = hi, f.stiffnessRatio = hi / lo;
  return f;
}

bool finiteState(const State& s) {
  for (const Vec3& p : s.positions)
    if (!p.allFinite()) return false;
  for (const Vec3& v : s.velocities)
    if (!v.allFinite()) return false;
  return true;
}

std::string likelyCause(const DivergenceFacts& f, const Metrics& now) {
  char buf[512];
  if (f.forwardEuler)
    return "the likely cause is the forward_euler integrator, which gains energy at any dt (set simulation.integrator "
           "to \"symplectic\" or \"implicit\", or a much smaller dt)";
  const double safeFraction = f.period > 0 ? 0.5 * f.stableDt / f.period : 0;
  if (f.explicitStep && f.stableDt > 0 && f.dt > 0.9 * f.stableDt) {
    if (f.dtGiven)
      std::snprintf(buf, sizeof buf,
                    "the likely cause is simulation.dt = %.3g s, %.2g x the measured stability limit of about %.3g s "
                    "(2 / omega_max): set simulation.dt to %.2g s or less, or \"auto\"",
                    f.dt, f.dt / f.stableDt, f.stableDt, 0.5 * f.stableDt);
    else
      std::snprintf(buf, sizeof buf,
                    "the likely cause is simulation.dt_fraction = %.3g (dt = %.3g s), %.2g x the measured stability "
                    "limit of about %.3g s (dt_fraction %.2g; 2 / omega_max): set "
                    "simulation.dt_fraction to %.2g or less",
                    f.dtFraction, f.dt, f.dt / f.stableDt, f.stableDt, f.period > 0 ? f.stableDt / f.period : 0.0,
                    safeFraction);
    return buf;
  }
  const char* dtKey = f.dtGiven ? "simulation.dt" : "simulation.dt_fraction";
  const double perStep = f.voxelSize > 0 ? f.dt / f.voxelSize : 0;
  if (f.manipulatorSpeed * perStep > 0.5) {
    std::snprintf(buf, sizeof buf,
                  "the likely cause is a manipulator moving at %.3g m/s, %.2g voxels (%.3g m) per step: slow its path "
                  "or lower %s (dt = %.3g s)",
                  f.manipulatorSpeed, f.manipulatorSpeed * perStep, f.voxelSize, dtKey, f.dt);
    return buf;
  }
  if (f.bodySpeed * perStep > 0.5) {
    std::snprintf(buf, sizeof buf,
                  "the likely cause is an impact at %.3g m/s, %.2g voxels (%.3g m) per step: lower %s (dt = %.3g s) "
                  "or the bodies' speed",
                  f.bodySpeed, f.bodySpeed * perStep, f.voxelSize, dtKey, f.dt);
    return buf;
  }
  if (f.stiffnessRatio > 100) {
    std::snprintf(buf, sizeof buf,
                  "the likely cause is the stiffness ratio %.3g of the materials (youngs_modulus %.3g to %.3g Pa): "
                  "lower %s (dt = %.3g s) or bring the materials' youngs_modulus closer",
                  f.stiffnessRatio, f.softE, f.stiffE, dtKey, f.dt);
    return buf;
  }
  if (now.minElementDet < 0) {
    std::snprintf(buf, sizeof buf,
                  "the likely cause is inverted elements (min element det %.3g) at dt = %.3g s (stability limit about "
                  "%.3g s): lower %s or raise simulation.damping",
                  now.minElementDet, f.dt, f.stableDt, dtKey);
    return buf;
  }
  std::snprintf(buf, sizeof buf, "no single cause measured (dt = %.3g s, stability limit about %.3g s): lower %s",
                f.dt, f.stableDt, dtKey);
  return buf;
}

std::optional<std::string> DivergenceGuard::check(const Metrics& m, double contactWork, const std::string& cause,
                                                  std::string* warning) {
  char buf[800];
  const double energy = m.kineticEnergy + m.elasticEnergy;
  const double allowed = allowedEnergy(budget_, settings_, m, contactWork);
  if (!std::isfinite(energy) || energy > allowed) {
    std::snprintf(buf, sizeof buf,
                  "simulation diverged at t = %.4g s: kinetic + elastic energy %.3g J is over %.3g J, %g x what the "
                  "initial state (%.3g J), gravity, manipulators (up to %.3g m/s) and the contacts' work (%.3g J) can "
                  "have supplied (min element det %.3g); %s",
                  m.time, energy, allowed, settings_.energyFactor,
                  budget_.initial.kineticEnergy + budget_.initial.elasticEnergy, budget_.drivenSpeed, contactWork,
                  m.minElementDet, cause.c_str());
    return std::string(buf);
  }
  if (m.minElementDet < 0) {
    if (invertedFrames_++ == 0) invertedSince_ = m.time;
    if (!warned_ && invertedFrames_ >= settings_.inversionFrames && m.time - invertedSince_ >= settings_.inversionSeconds) {
      warned_ = true;
      std::snprintf(buf, sizeof buf,
                    "warning: elements inverted (min element det %.3g) in %d frames running, from t = %.4g to %.4g s "
                    "(kinetic + elastic energy %.3g J, within what was supplied); the run goes on, they may recover",
                    m.minElementDet, invertedFrames_, invertedSince_, m.time, energy);
      if (warning) *warning = buf;
    }
  } else {
    invertedFrames_ = 0;
    warned_ = false;
  }
  return std::nullopt;
}

}  // namespace gradel
