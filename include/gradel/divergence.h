// Divergence guard of a run: a body that blew up with walls around it keeps finite numbers, so
// "diverged" is judged on physics, once per written frame, from World::metrics():
//   * energy: kinetic + elastic energy far above what the initial state, gravity, the
//     manipulators' speed, the work of external forces (external_force.h) and the work the
//     contacts did (World::contactWork(), contact_work.h:
//     a tool inside a body, a crush, a fast strike, start overlaps pushed apart) can have
//     supplied (an energy budget with a generous factor). Only this, or a non-finite state, is a
//     divergence (exit 3).
//   * persistent inversion: some element turned inside out (min det < 0) for many frames
//     running. A crushed or struck body inverts elements and recovers (issue 26: a ball crossed
//     by a tool at 1000 m/s is back in shape within a second), so this is a warning only.
// The check is a pure function of the budget and the metrics; DivergenceGuard only counts the
// frames of an inversion. The message names the cause it measured (likelyCause).
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
///   factor x (KE0 + E0 + max(0, G0 - G) + 1/2 M (2 u)^2 + 1/2 M slack^2 + W),
/// with G the gravity energy (metrics), u the fastest manipulator, W the work the contacts did
/// so far (World::contactWork()). Infinite when unbounded.
double allowedEnergy(const EnergyBudget& budget, const DivergenceSettings& settings, const Metrics& now,
                     double contactWork = 0);

/// The work [J] the world was supplied from outside so far, what the guard's `contactWork`
/// argument takes: the contacts' (World::contactWork()) plus the external forces'
/// (World::externalWork(), external_force.h).
double suppliedWork(const World& world);

/// The fastest speed of a path over [0, duration] [m/s] (sampled at every key and 64 points per
/// segment, plus the velocity kept after the last key).
double maxPathSpeed(const Path& path, double duration);
/// The budget of a world at t = 0: its metrics, mass, manipulator and pin paths.
EnergyBudget energyBudget(const World& world, double duration);

/// What the messages can name as a cause, measured from the world at t = 0 (divergenceFacts).
struct DivergenceFacts {
  bool forwardEuler = false;
  bool explicitStep = true;     ///< symplectic or forward Euler (dt bounded by stability).
  bool dtGiven = false;         ///< simulation.dt was set (else dt_fraction of the period rule).
  double dt = 0;                ///< [s]
  double dtFraction = 0;        ///< simulation.dt_fraction as applied.
  double period = 0;            ///< [s] the period dt_fraction multiplies.
  double stableDt = 0;          ///< [s] the explicit step's stability limit, 2 / omega of the stiffest vertex.
  double manipulatorSpeed = 0;  ///< [m/s] fastest manipulator on its path.
  double bodySpeed = 0;         ///< [m/s] fastest vertex at t = 0 (bodies thrown at each other).
  double voxelSize = 0;         ///< [m] smallest voxel edge of the bodies.
  double stiffnessRatio = 1;    ///< largest over smallest Young's modulus of the bodies and regions.
  double softE = 0, stiffE = 0;  ///< [Pa] those two.
};
DivergenceFacts divergenceFacts(const World& world, double duration);

/// Whether every position and velocity of the state is finite: the check every front end (the
/// CLI's `run` and `render`, the viewer, the web page, Python) makes between chunks of steps; a
/// non-finite state is a divergence whatever the energy says.
bool finiteState(const State& s);

/// The likely cause and the setting that fixes it, from what was measured: dt against the
/// stability limit, a manipulator's or a body's speed per step against the voxel size, the
/// stiffness ratio of the materials, else the inverted elements of `now`.
std::string likelyCause(const DivergenceFacts& facts, const Metrics& now);

class DivergenceGuard {
 public:
  DivergenceGuard(EnergyBudget budget, DivergenceSettings settings = {}) : budget_(budget), settings_(settings) {}
  /// The reason the run diverged, or nothing while it is plausible. `contactWork` is what the
  /// contacts and external forces supplied so far (suppliedWork(world)); `cause` names the likely culprit for the
  /// message. A persistent inversion sets `*warning` (once per inversion that lasts) and is not
  /// a divergence.
  std::optional<std::string> check(const Metrics& m, double contactWork, const std::string& cause,
                                   std::string* warning = nullptr);

 private:
  EnergyBudget budget_;
  DivergenceSettings settings_;
  int invertedFrames_ = 0;
  double invertedSince_ = 0;
  bool warned_ = false;  ///< The current inversion was reported.
};

}  // namespace gradel
