// Divergence guard of a run: a body that blew up with walls around it keeps finite numbers, so
// "diverged" is judged on physics, once per written frame, from World::metrics():
//   * energy: kinetic + elastic energy far above what the initial state, gravity and the
//     manipulators can have supplied (an energy budget with a generous factor);
//   * persistent inversion: some element turned inside out (min det < 0) for many frames
//     running, which a healthy explicit run does not do for long.
// The check is a pure function of the budget and the metrics; DivergenceGuard only counts the
// frames of an inversion.
#pragma once

#include <optional>
#include <string>

#include "gradel/world.h"

namespace gradel {

struct DivergenceSettings {
  double energyFactor = 10;       ///< Allowed multiple of the energy budget.
  double slackSpeed = 1.0;        ///< [m/s] the budget always holds 1/2 M slackSpeed^2 (rounding, small bodies).
  int inversionFrames = 10;       ///< Consecutive frames with min det < 0 ...
  double inversionSeconds = 0.1;  ///< ... spanning at least this simulated time [s].
};

/// What can have put energy into the body.
struct EnergyBudget {
  Metrics initial;         ///< Metrics at t = 0.
  double mass = 0;         ///< [kg] total mass of the body.
  double drivenSpeed = 0;  ///< [m/s] fastest manipulator (an elastic hit gives at most 2x its speed).
  bool unbounded = false;  ///< Moving pins do work the budget cannot bound: the energy check is off.
};

/// Kinetic + elastic energy now that the budget allows [J]:
///   factor x (KE0 + E0 + max(0, G0 - G) + 1/2 M (2 u)^2 + 1/2 M slack^2),
/// with G the gravity energy (metrics), u the fastest manipulator. Infinite when unbounded.
double allowedEnergy(const EnergyBudget& budget, const DivergenceSettings& settings, const Metrics& now);

/// The fastest speed of a path over [0, duration] [m/s] (sampled at every key and 64 points per
/// segment, plus the velocity kept after the last key).
double maxPathSpeed(const Path& path, double duration);
/// The budget of a world at t = 0: its metrics, mass, manipulator and pin paths.
EnergyBudget energyBudget(const World& world, double duration);

class DivergenceGuard {
 public:
  DivergenceGuard(EnergyBudget budget, DivergenceSettings settings = {}) : budget_(budget), settings_(settings) {}
  /// The reason the run diverged, or nothing while it is plausible. `cause` names the likely
  /// culprit for the message (dt, dt_fraction, integrator).
  std::optional<std::string> check(const Metrics& m, const std::string& cause);

 private:
  EnergyBudget budget_;
  DivergenceSettings settings_;
  int invertedFrames_ = 0;
  double invertedSince_ = 0;
};

}  // namespace gradel
