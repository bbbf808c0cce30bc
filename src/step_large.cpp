// The large step's advance (large_step.h): midpoint substeps away from contacts, the implicit
// advance (step_implicit.cpp) for a step that could touch anything.
#include <algorithm>
#include <limits>

#include "step_context.h"

namespace gradel {

// Large step (large_step.h): midpoint substeps away from contacts. A step that could touch
// anything is a projective-dynamics step with held contacts (stepImplicit: backward Euler, the
// holds one-sided constraints of a filtered PCG, fast manipulators swept): the midpoint keeps
// whatever energy a contact projection puts into the deformation, and in contact-rich scenes
// (grasp at E x1) that blew the body up within 0.1 s (measured, with the projection after the
// midpoint and with contact forces inside its solve); a Newton-PCG backward-Euler step with the
// held vertices as constraints of its CG needed 40-80 CG iterations to stay stable on the grasp
// scenes at E x100 (20 inverted elements), 2-5x the cost of this step.
// A step touches if the last one did, or a vertex's free-flight end point or its start is within
// the smallest element's size of a surface (manipulators at their end-of-step pose), or a
// manipulator moves more than half its radius within the step.
void World::stepLargeStep() {
  StepContext& c = *scratch_;
  const int substeps = sim_.largeStepSubsteps;
  if (!largeStep_)
    largeStep_ =
        std::make_unique<LargeStepSolver>(*model_, dt_ / substeps, pinSet_.vertices, sim_.largeStepCoarseNodes);
  largeStep_->setTeam(frameStepTeam());  // element forces and factor solves (the same bits at any count)
  // Contacts between bodies are constraints of the implicit step; obstacles near: its held contacts.
  const bool bodiesNear = bodyContactsMayTouch();
  if (!bodiesNear) clearBodyPairLambdas();
  if (bodiesNear || (c.obstacles && largeStepNearObstacles())) {
    stepImplicit(true);
    largeStep_->resetEnergyBudget();  // the contacts did work
    return;
  }
  if (c.obstacles) c.previousPositions = state_.positions, c.previousVelocities = state_.velocities;
  c.contactDepth.assign(model_->numVertices(), 0.0);
  for (int k = 0; k < substeps; ++k) {
    const std::vector<Vec3> pinStart = pinTargets(state_.time + dt_ * k / substeps);
    const std::vector<Vec3> pinEnd = pinTargets(k + 1 == substeps ? c.tNext : state_.time + dt_ * (k + 1) / substeps);
    largeStep_->step(state_.positions, state_.velocities, state_.rotations, c.gravity, sim_.damping,
                     sim_.largeStepPasses, sim_.rotationIterations, pinStart, pinEnd);
  }
  moveManipulators(c.tNext);
  if (c.obstacles) {
    stageContacts(0, model_->numVertices());  // the guarantee: no vertex left inside
    if (std::any_of(c.contactDepth.begin(), c.contactDepth.end(), [](Real d) { return d > 0; }))
      largeStep_->resetEnergyBudget();
  }
  finishFrameStep(c.tNext);
}

// Whether the step could touch a manipulator or a wall, from a prediction (nothing is moved):
// the manipulators at their end-of-step poses, each vertex at its start and free-flight end.
bool World::largeStepNearObstacles() const {
  const StepContext& c = *scratch_;
  if (c.maxContactDepth > 0) return true;  // the last step touched
  std::vector<Manipulator> atEnd = manipulators_;
  for (Manipulator& m : atEnd)
    if (!m.settings.path.keys.empty()) m.position = m.settings.path.position(c.tNext);
  const int dim = model_->dim;
  auto gap = [&](const Vec3& p) {
    Real best = std::numeric_limits<Real>::infinity();
    for (const Manipulator& mp : atEnd) best = std::min(best, mp.signedDistance(p, nullptr));
    if (domain_.enabled)
      for (int a = 0; a < dim; ++a) best = std::min({best, p[a] - domain_.min[a], domain_.max[a] - p[a]});
    return best;
  };
  const Real margin = *std::min_element(model_->size.begin(), model_->size.end());
  for (size_t i = 0; i < model_->numVertices(); ++i) {
    const Vec3& x = state_.positions[i];
    if (gap(freeFlight(x, state_.velocities[i], dt_, 0.5, c.gravity)) < margin || gap(x) < margin) return true;
  }
  for (size_t k = 0; k < atEnd.size(); ++k)
    if ((atEnd[k].position - manipulators_[k].position).norm() > 0.5 * atEnd[k].settings.radius) return true;
  return false;
}

}  // namespace gradel
