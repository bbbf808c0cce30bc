// How many simulation steps the viewer's stepping thread takes next, so that simulated time keeps
// up with wall time (times a speed) without ever holding the world for long: the steps real time
// owes, in batches that fit a wall-time budget at the measured cost per step, and, when the
// simulation cannot keep up, the debt dropped rather than caught up. Pure: the caller passes the
// wall clock and the measured batch times (tests/test_step_pacer.cpp drives it with made-up ones).
#pragma once

namespace gradel {

class StepPacer {
 public:
  struct Limits {
    double batchSeconds = 0.004;  ///< [s] wall time one batch may hold the world (>= 1 step)
    double maxLagSeconds = 0.1;   ///< [s] wall; a larger debt is dropped, not caught up
    double behindHoldSeconds = 1; ///< [s] behind() stays true this long after a dropped debt
  };

  /// `dt` [s] simulated per step; `speed` simulated seconds wanted per wall second.
  explicit StepPacer(double dt, double speed = 1);
  StepPacer(double dt, double speed, Limits limits);

  /// Starts owing real time from `wallNow` (also after a pause: the paused time is not owed).
  void restart(double wallNow);
  /// A new speed from `wallNow` on (what was owed before is kept).
  void setSpeed(double speed, double wallNow);

  /// The steps of the next batch at `wallNow`: those owed, at most the batch budget's worth at the
  /// measured cost per step (one step while no cost has been measured); 0 when none is owed.
  long due(double wallNow);
  /// A batch of `steps` steps took `seconds` of wall time.
  void stepped(long steps, double seconds);
  /// [s] wall until the next step is owed (0 when one is owed now).
  double waitSeconds(double wallNow) const;

  /// True while the simulation runs slower than wanted (a debt was dropped within the hold time).
  bool behind(double wallNow) const { return wallNow < behindUntil_; }
  /// [s] wall per step, a moving average of the measured batches (0 before the first).
  double secondsPerStep() const { return secondsPerStep_; }
  /// Simulated seconds the machine could run per wall second at the measured cost (dt / cost).
  double capacity() const { return secondsPerStep_ > 0 ? dt_ / secondsPerStep_ : 0; }
  double dt() const { return dt_; }
  double speed() const { return speed_; }

 private:
  double owedSteps(double wallNow) const;

  double dt_, speed_;
  Limits limits_;
  double anchorWall_ = 0;  ///< wall time from which steps are owed
  double stepsSinceAnchor_ = 0;
  double secondsPerStep_ = 0;
  double behindUntil_ = -1;
};

}  // namespace gradel
