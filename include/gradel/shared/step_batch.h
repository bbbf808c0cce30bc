// One batch of a real-time front end's steps: the steps a frame (the web page) or a paced batch
// (the viewer's stepping thread, step_pacer.h) owes, each after the caller's per-step hook (a
// dragged manipulator fed along its path, render/manipulator_drag.h), cut short when a wall-time
// budget runs out, and whether the state is still finite after it. `gradel run` / `gradel render`
// step by frames instead (frame_loop.h); Python's step / advance_to are not paced.
#pragma once

#include <algorithm>
#include <cmath>
#include <functional>

#include "gradel/world.h"

namespace gradel {

/// The whole steps that `simSeconds` of simulated time take at `dt`, at least one.
inline long stepsFor(double simSeconds, double dt) { return std::max(1L, std::lround(simSeconds / dt)); }

struct StepBatchOptions {
  /// [s] wall time the batch may take: after a step that ends past it, no further step (0: none).
  double budgetSeconds = 0;
  /// Called before each step with the fraction of the batch done after it ((k + 1) / steps).
  std::function<void(double fraction)> beforeStep;
};

struct StepBatch {
  long steps = 0;      ///< Steps taken.
  bool cut = false;    ///< The budget ran out before all were taken.
  bool finite = true;  ///< The state after the batch is finite (divergence.h finiteState).
};

/// Takes `steps` steps of `world` (fewer when the budget runs out; none when steps <= 0).
StepBatch stepBatch(World& world, long steps, const StepBatchOptions& options = {});

}  // namespace gradel
