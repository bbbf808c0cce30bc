// How long a run will take, estimated before it starts (docs/scenes.md, "Limits"): a dt of
// 1e-12 s makes 0.01 s of simulated time 1e10 steps, which would hang the CLI for days. The
// estimate is refused beyond a default budget unless the user asks for that many steps.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "gradel/integrator.h"

namespace gradel {

/// Default budget of `gradel run`: 10^7 steps and 10^11 vertex-steps (about an hour at the
/// explicit integrators' ~30 ns per vertex-step).
inline constexpr double kDefaultMaxSteps = 1e7;
inline constexpr double kDefaultMaxVertexSteps = 1e11;
/// Wall time of one vertex-step [s]: explicit (measured 11-30 ns, README "speed") and implicit
/// (~4 us on the 12^3 strike scene, projective.h) integrators, rounded up.
inline constexpr double kExplicitSecondsPerVertexStep = 30e-9;
inline constexpr double kImplicitSecondsPerVertexStep = 4e-6;

struct RunEstimate {
  double steps = 0;        ///< ceil(duration / dt)
  double vertexSteps = 0;  ///< steps x vertices
  double wallSeconds = 0;  ///< vertexSteps x seconds per vertex-step of the integrator
};

RunEstimate estimateRun(double duration, double dt, size_t vertices, IntegratorKind integrator);

/// Throws InputError when the estimate is over the budget: with `maxSteps` (--max-steps N) only
/// the step count is checked against N; without it, against kDefaultMaxSteps and
/// kDefaultMaxVertexSteps. The message gives the estimate and how to proceed.
void checkRunBudget(const RunEstimate& e, double dt, double duration, std::optional<double> maxSteps);

/// "3.2 h", "45 s", "12 days": a duration for messages.
std::string formatSeconds(double seconds);

}  // namespace gradel
