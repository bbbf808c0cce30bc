#include "gradel/shared/frame_loop.h"

#include <cmath>
#include <limits>
#include <sstream>

namespace gradel {

namespace {
constexpr double kMaxFrames = 1e6;
std::string num(double x) {
  std::ostringstream o;
  o << x;
  return o.str();
}
}  // namespace

FrameSchedule frameSchedule(Real start, Real duration, Real interval, Real dt, std::optional<long> frames) {
  FrameSchedule s;
  s.start = start;
  s.interval = interval;
  if (interval < dt) s.interval = dt, s.intervalRaisedToDt = true;
  if (frames) {
    if (*frames < 1 || *frames > kMaxFrames)
      throw InputError("", "frames", "must be in [1, 1000000] (got " + std::to_string(*frames) + ")");
    s.frames = size_t(*frames);
    s.end = std::numeric_limits<Real>::infinity();
    return s;
  }
  s.end = start + duration;
  // Frames after the first; the last one lands exactly on the end.
  const double after = std::ceil(duration / s.interval - 1e-9);
  if (after > kMaxFrames)
    throw InputError("", "frame_interval",
                     num(s.interval) + " s gives " + num(after) + " frames (expected at most 1000000 frames)");
  s.frames = size_t(std::max(1.0, after)) + 1;
  return s;
}

size_t runFrames(World& world, const FrameSchedule& s, const std::function<void(size_t)>& onFrame,
                 const FrameLoopChecks& checks) {
  constexpr Real kChunkSteps = 32;
  const Real dt = world.dt();
  const Real span = std::isfinite(s.end) ? s.end - s.start : Real(s.frames - 1) * s.interval;
  size_t written = 0;
  Real lastFrameTime = -std::numeric_limits<Real>::infinity();
  for (size_t f = 0; f < s.frames; ++f) {
    const Real tFrame = s.time(f);
    while (world.time() < tFrame - 0.5 * dt) {
      const Real before = world.time();
      world.advanceTo(std::min(tFrame, before + kChunkSteps * dt));
      if (world.time() == before) world.step();  // never spin without progress
      if (checks.afterChunk) checks.afterChunk();
      if (checks.progress) checks.progress(span > 0 ? (world.time() - s.start) / span : 1.0);
    }
    if (world.time() > lastFrameTime) {
      onFrame(written++);
      lastFrameTime = world.time();
      world.restartForceAverage();  // each frame's contact forces average the steps since the previous frame
    }
  }
  return written;
}

}  // namespace gradel
