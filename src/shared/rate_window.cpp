#include "gradel/shared/rate_window.h"

namespace gradel {

void RateWindow::add(double wall, double simTime, long steps) {
  samples_.push_back({wall, simTime, steps});
  // Keep the newest sample at or before the window's start, so the rate spans a full window.
  while (samples_.size() > 2 && wall - samples_[1].wall >= window_) samples_.pop_front();
}

double RateWindow::realTimeFactor() const {
  const double s = span();
  return s > 0 ? (samples_.back().simTime - samples_.front().simTime) / s : 0;
}

double RateWindow::stepsPerSecond() const {
  const double s = span();
  return s > 0 ? double(samples_.back().steps - samples_.front().steps) / s : 0;
}

double RateWindow::samplesPerSecond() const {
  const double s = span();
  return s > 0 ? double(samples_.size() - 1) / s : 0;
}

}  // namespace gradel
