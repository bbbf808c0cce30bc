// Rates over the last second of wall time, for the viewer's live figures: simulated seconds per
// wall second (the real-time factor), steps and frames per second. Each sample is (wall time,
// simulated time, steps so far); a rate is the difference between the newest sample and the
// oldest one within the window, so it is honest (no average of per-frame ratios, nothing kept from
// before the window or before a reset).
#pragma once

#include <deque>

namespace gradel {

class RateWindow {
 public:
  explicit RateWindow(double windowSeconds = 1.0) : window_(windowSeconds) {}

  /// A sample at wall time `wall` [s]: simulated time `simTime` [s] and `steps` taken so far.
  void add(double wall, double simTime, long steps);
  /// Forgets every sample (a rebuild, a reset, a pause).
  void reset() { samples_.clear(); }

  /// Simulated seconds per wall second over the window; 0 with fewer than two samples.
  double realTimeFactor() const;
  double stepsPerSecond() const;
  /// Samples per wall second (the viewer adds one a frame: frames per second).
  double samplesPerSecond() const;
  /// [s] wall between the oldest and newest sample.
  double span() const { return samples_.size() < 2 ? 0 : samples_.back().wall - samples_.front().wall; }

 private:
  struct Sample {
    double wall, simTime;
    long steps;
  };
  double window_;
  std::deque<Sample> samples_;
};

}  // namespace gradel
