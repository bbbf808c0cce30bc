#include "gradel/shared/step_batch.h"

#include <chrono>

#include "gradel/divergence.h"

namespace gradel {

StepBatch stepBatch(World& world, long steps, const StepBatchOptions& options) {
  using Clock = std::chrono::steady_clock;
  const Clock::time_point start = Clock::now();
  StepBatch b;
  while (b.steps < steps) {
    if (options.beforeStep) options.beforeStep(double(b.steps + 1) / double(steps));
    world.step();
    ++b.steps;
    if (options.budgetSeconds > 0 && b.steps < steps &&
        std::chrono::duration<double>(Clock::now() - start).count() > options.budgetSeconds) {
      b.cut = true;
      break;
    }
  }
  b.finite = finiteState(world.state());
  return b;
}

}  // namespace gradel
