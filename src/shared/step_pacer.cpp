#include "gradel/shared/step_pacer.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace gradel {

StepPacer::StepPacer(double dt, double speed) : StepPacer(dt, speed, Limits{}) {}

StepPacer::StepPacer(double dt, double speed, Limits limits) : dt_(dt), speed_(speed), limits_(limits) {
  if (!(dt > 0) || !(speed > 0) || !(limits.batchSeconds > 0) || !(limits.maxLagSeconds > 0))
    throw std::invalid_argument("StepPacer: dt, speed and limits must be > 0");
}

void StepPacer::restart(double wallNow) {
  anchorWall_ = wallNow;
  stepsSinceAnchor_ = 0;
}

void StepPacer::setSpeed(double speed, double wallNow) {
  if (!(speed > 0)) throw std::invalid_argument("StepPacer: speed must be > 0");
  const double owed = owedSteps(wallNow);
  speed_ = speed;
  restart(wallNow);
  stepsSinceAnchor_ = -owed;  // the debt carries over at the new speed
}

double StepPacer::owedSteps(double wallNow) const {
  return (wallNow - anchorWall_) * speed_ / dt_ - stepsSinceAnchor_;
}

long StepPacer::due(double wallNow) {
  double owed = owedSteps(wallNow);
  // A debt of more than maxLag wall seconds' worth is dropped: the simulation runs slower than
  // wanted, and catching up later would make it run faster than real time.
  const double maxOwed = limits_.maxLagSeconds * speed_ / dt_;
  if (owed > std::max(maxOwed, 1.0)) {
    stepsSinceAnchor_ += owed - std::max(maxOwed, 1.0);
    owed = std::max(maxOwed, 1.0);
    behindUntil_ = wallNow + limits_.behindHoldSeconds;
  }
  if (owed < 1) return 0;
  const double fit = secondsPerStep_ > 0 ? limits_.batchSeconds / secondsPerStep_ : 1;
  return std::max(1L, long(std::floor(std::min(owed, fit))));
}

void StepPacer::stepped(long steps, double seconds) {
  if (steps <= 0) return;
  stepsSinceAnchor_ += double(steps);
  const double perStep = std::max(seconds, 0.0) / double(steps);
  secondsPerStep_ = secondsPerStep_ > 0 ? 0.8 * secondsPerStep_ + 0.2 * perStep : perStep;
}

double StepPacer::waitSeconds(double wallNow) const {
  const double owed = owedSteps(wallNow);
  return owed >= 1 ? 0 : (1 - owed) * dt_ / speed_;
}

}  // namespace gradel
