#include "gradel/run_budget.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "gradel/types.h"

namespace gradel {

RunEstimate estimateRun(double duration, double dt, size_t vertices, IntegratorKind integrator) {
  RunEstimate e;
  e.steps = std::ceil(duration / dt - 1e-9);
  e.vertexSteps = e.steps * double(vertices);
  e.wallSeconds = e.vertexSteps * (integrator == IntegratorKind::Implicit ? kImplicitSecondsPerVertexStep
                                                                          : kExplicitSecondsPerVertexStep);
  return e;
}

std::string formatSeconds(double s) {
  char buf[48];
  if (!std::isfinite(s))
    std::snprintf(buf, sizeof buf, "forever");
  else if (s < 120)
    std::snprintf(buf, sizeof buf, "%.0f s", s);
  else if (s < 7200)
    std::snprintf(buf, sizeof buf, "%.0f min", s / 60);
  else if (s < 172800)
    std::snprintf(buf, sizeof buf, "%.1f h", s / 3600);
  else
    std::snprintf(buf, sizeof buf, "%.3g days", s / 86400);
  return buf;
}

void checkRunBudget(const RunEstimate& e, double dt, double duration, std::optional<double> maxSteps) {
  const bool over =
      maxSteps ? e.steps > *maxSteps : e.steps > kDefaultMaxSteps || e.vertexSteps > kDefaultMaxVertexSteps;
  if (!over) return;
  char buf[512];
  std::snprintf(buf, sizeof buf,
                "simulation: %.3g s at dt = %.3g s is %.3g steps (%.3g vertex-steps, about %s of wall time), over the "
                "limit of %.3g steps%s; use a larger simulation.dt or dt_fraction, a shorter duration, or pass "
                "--max-steps %.0f to run it anyway",
                duration, dt, e.steps, e.vertexSteps, formatSeconds(e.wallSeconds).c_str(),
                maxSteps ? *maxSteps : kDefaultMaxSteps, maxSteps ? "" : " and 1e+11 vertex-steps",
                std::min(e.steps, 1e18));
  throw InputError(buf);
}

}  // namespace gradel
