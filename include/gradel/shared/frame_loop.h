// The one frame loop of `gradel run` and `gradel render`: which simulated times get a frame, and
// the loop that advances a World from frame to frame in chunks of steps, with the checks a long
// run needs between chunks (divergence, a stop request, progress). The callers own what a frame
// is (VTK files and metrics, or pictures and surface files).
#pragma once

#include <functional>
#include <optional>

#include "gradel/world.h"

namespace gradel {

/// The frames of a run from `start` over `duration` [s] every `interval` [s]: frame 0 at start,
/// frame f at start + f interval, the last one exactly at start + duration when the duration is
/// not a whole number of intervals. At most one frame per step: an interval below dt becomes dt.
struct FrameSchedule {
  Real start = 0;                   ///< [s] time of frame 0.
  Real end = 0;                     ///< [s] no frame after this time (start + duration).
  Real interval = 0;                ///< [s] between frames (>= dt).
  size_t frames = 1;                ///< Frames including frame 0.
  bool intervalRaisedToDt = false;  ///< The interval asked for was below dt (callers may say so).
  /// Time of frame f [s].
  Real time(size_t f) const { return std::min(start + Real(f) * interval, end); }
};

/// The schedule of the whole duration, or of exactly `frames` frames (which may run past the
/// duration). Throws InputError naming `frame_interval` when the duration would take more than
/// 10^6 frames, and `frames` when a given count is not in [1, 10^6].
FrameSchedule frameSchedule(Real start, Real duration, Real interval, Real dt, std::optional<long> frames = {});

/// Called between chunks of steps: `afterChunk` may throw to stop the run (divergence, a signal);
/// `progress` gets the fraction of the schedule done.
struct FrameLoopChecks {
  std::function<void()> afterChunk;
  std::function<void(double fraction)> progress;
};

/// Advances `world` through the schedule, calling onFrame(index) at each frame time reached
/// (index 0, 1, ... in order), then restarts the world's contact force average (so that a frame's
/// World::averageContactForces() covers the steps since the previous frame). Steps go in chunks of at most 32 (the same steps as one
/// World::advanceTo per frame), so that the checks run within a frame. Frames land on distinct
/// steps: a frame time that no further step reaches (the last one, when the duration ends less
/// than half a step past the previous frame) is skipped. Returns the frames written.
size_t runFrames(World& world, const FrameSchedule& schedule, const std::function<void(size_t index)>& onFrame,
                 const FrameLoopChecks& checks = {});

}  // namespace gradel
