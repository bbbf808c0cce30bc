// The integrator and period-rule names, and "auto"'s choice of integrator by its cost model
// (integrator.h).
#include <cmath>
#include <cstdio>

#include "step_context.h"

namespace gradel {

IntegratorKind parseIntegratorKind(const std::string& name) {
  if (name == "symplectic") return IntegratorKind::SymplecticEuler;
  if (name == "forward_euler") return IntegratorKind::ForwardEuler;
  if (name == "implicit") return IntegratorKind::Implicit;
  if (name == "large_step") return IntegratorKind::LargeStep;
  if (name == "auto") return IntegratorKind::Auto;
  throw InputError("unknown integrator '" + name +
                   "' (expected symplectic, forward_euler, implicit, large_step or auto)");
}

const char* integratorKindName(IntegratorKind k) {
  if (k == IntegratorKind::Implicit) return "implicit";
  if (k == IntegratorKind::LargeStep) return "large_step";
  if (k == IntegratorKind::Auto) return "auto";
  return k == IntegratorKind::ForwardEuler ? "forward_euler" : "symplectic";
}

PeriodRule parsePeriodRule(const std::string& name) {
  if (name == "operator") return PeriodRule::Operator;
  if (name == "vertex") return PeriodRule::Vertex;
  if (name == "element") return PeriodRule::Element;
  throw InputError("unknown period rule '" + name + "' (expected operator, vertex or element)");
}

const char* periodRuleName(PeriodRule r) {
  if (r == PeriodRule::Operator) return "operator";
  return r == PeriodRule::Element ? "element" : "vertex";
}

Real defaultDtFraction(PeriodRule r) { return r == PeriodRule::Operator ? 0.175 : 0.1; }
Real maxDtFraction(PeriodRule r) { return r == PeriodRule::Element ? 0.1 : 0.3; }


IntegratorCost integratorCost(size_t vertices, double explicitDt, double largeDt) {
  IntegratorCost c;
  c.explicitWallPerSecond = double(vertices) * kAutoExplicitSecondsPerVertexStep / explicitDt;
  const double perVertexStep =
      kAutoLargeStepSecondsPerVertexStep * std::pow(double(vertices) / kAutoLargeStepVertices, kAutoLargeStepExponent);
  c.largeStepWallPerSecond = double(vertices) * perVertexStep / largeDt;
  c.pick = c.largeStepWallPerSecond < c.explicitWallPerSecond ? IntegratorKind::LargeStep
                                                              : IntegratorKind::SymplecticEuler;
  return c;
}

// "auto": the integrator that costs less wall time per simulated second (integratorCost): the
// explicit step at its dt = auto against the large step at the scene's dt (or one 1/60 s frame).
void World::chooseIntegrator(Real period) {
  const Real explicitDt = sim_.dtFraction * period, largeDt = sim_.dt > 0 ? sim_.dt : 1.0 / 60.0;
  const IntegratorCost c = integratorCost(model_->numVertices(), explicitDt, largeDt);
  sim_.integrator = c.pick;
  // A scene's dt is what the large step would take; the explicit step keeps its stable one.
  if (c.pick == IntegratorKind::SymplecticEuler && sim_.dt > explicitDt) sim_.dt = 0;
  char buf[320];
  const bool explicitPick = c.pick == IntegratorKind::SymplecticEuler;
  std::snprintf(buf, sizeof buf,
                "%s: ~%.2g s per simulated s (symplectic at dt %.3g s: ~%.2g s; large_step at %.3g s: ~%.2g s; "
                "2 threads, measured cost model)",
                explicitPick ? "symplectic" : "large_step",
                explicitPick ? c.explicitWallPerSecond : c.largeStepWallPerSecond, explicitDt,
                c.explicitWallPerSecond, largeDt, c.largeStepWallPerSecond);
  integratorChoice_ = buf;
}

}  // namespace gradel
