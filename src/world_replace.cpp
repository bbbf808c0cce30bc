// World::replaceModel: the least invasive correct path to a world over a new model (a carved body,
// carve_scene.h): a world made anew from the settings as applied, with dt following the new model
// (below), then everything that outlives a step moved over from this one; and carving's
// ledger of removed material (World::recordRemoval).
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "gradel/integrator.h"
#include "gradel/stability.h"
#include "gradel/stability_warm.h"
#include "gradel/world.h"
#include "plane.h"
#include "thread_team.h"

namespace gradel {

void World::replaceModel(std::shared_ptr<const RestModel> model, State state, std::vector<ContactBody> contactBodies,
                         const std::vector<PinSettings>* pins, const std::vector<uint32_t>* fromVertex) {
  if (!model) throw std::invalid_argument("World::replaceModel: no model");
  if (state.positions.size() != model->numVertices() || state.velocities.size() != model->numVertices() ||
      state.rotations.size() != model->numElements())
    throw std::invalid_argument("World::replaceModel: the state's sizes are not the model's");
  // dt = auto of the explicit step follows the new model. Under the operator rule (the default) the
  // carved body's own fastest vibration is estimated again (stability.h, Lanczos: about 150
  // explicit steps' work, small beside the re-layout), so dt is what a scene of the carved body
  // would get, shorter or longer. Under the vertex or element rule, or forward Euler (its damping
  // cap), dt is shortened by the ratio of the models' smallest vertex periods, never lengthened.
  const bool frameStep = sim_.integrator == IntegratorKind::Implicit || sim_.integrator == IntegratorKind::LargeStep;
  const bool estimate =
      sim_.dt == 0 && sim_.integrator == IntegratorKind::SymplecticEuler && sim_.dtPeriod == PeriodRule::Operator;
  SimulationSettings sim = sim_;  // estimate: the constructor's own dt = auto, Lanczos on the new model
  std::string rule = dtRule_;
  if (!estimate) {
    Real dt = dt_;
    const Real p0 = model_->smallestVertexPeriod, p1 = model->smallestVertexPeriod;
    if (sim_.dt == 0 && !frameStep && p1 > 0 && p1 < p0) {
      dt *= p1 / p0;
      const std::string shortened = " (shortened by carving)";  // said once, however many events
      const bool said = rule.size() >= shortened.size() &&
                        rule.compare(rule.size() - shortened.size(), shortened.size(), shortened) == 0;
      if (!said) rule += shortened;
    }
    sim.dt = dt;
    sim.dtPeriod = PeriodRule::Vertex;  // no estimate in the constructor: dt is given
  }
  // The estimate: warm started from the last one's Ritz vector carried over by fromVertex
  // (stability_warm.h), or from scratch keeping its Ritz vector for the next event.
  FrequencyEstimate frequency;
  std::vector<Vec3> ritz;
  if (estimate) {
    std::unique_ptr<ThreadTeam> team;  // the same bits at any thread count
    if (fromVertex && !ritz_.empty() && ritz_.size() == model_->numVertices() && fromVertex->size() == model->numVertices())
      frequency = highestFrequencyFrom(*model, stabilityWarmStart(*model_, *model, ritz_, *fromVertex),
                                       kWarmStartIterations, &ritz, estimateTeam(team));
    else
      frequency = highestFrequency(*model, 48, fromVertex ? &ritz : nullptr, estimateTeam(team));
  }
  World w(std::move(model), sim, domain_, {}, estimate ? &frequency : nullptr);
  w.ritz_ = std::move(ritz);
  w.sim_ = sim_;
  w.dtRule_ = estimate ? w.dtRule_ + " (estimated again after carving)" : rule;
  w.integratorChoice_ = integratorChoice_;
  if (!estimate) w.frequency_ = frequency_;
  w.state_ = std::move(state);
  for (Vec3& x : w.state_.positions) x = projectToPlane(x, w.model_->dim);  // a 2D state enters in its plane
  for (Vec3& v : w.state_.velocities) v = projectToPlane(v, w.model_->dim);
  // What may throw first (a pin that holds no vertex any more): this world is still untouched.
  const std::vector<PinSettings>& newPins = pins ? *pins : pins_;
  if (!newPins.empty()) w.setPins(newPins);
  w.bodyContactSettings_ = bodyContactSettings_;
  if (!contactBodies.empty())
    w.setBodyContacts(std::move(contactBodies), bodyContacts_ ? bodyContacts_->settings() : bodyContactSettings_);
  w.manipulators_ = std::move(manipulators_);
  w.manipulatorScale_ = std::move(manipulatorScale_), w.manipulatorSize_ = std::move(manipulatorSize_);
  w.manipulatorGrowth_ = std::move(manipulatorGrowth_);
  w.domainSet_ = domainSet_, w.wallsReleasing_ = wallsReleasing_, w.wallVelocity_ = wallVelocity_;
  w.startOverlaps_ = std::move(startOverlaps_);
  if (w.model_->bodies.size() == model_->bodies.size()) w.separations_ = std::move(separations_);
  w.stepForces_ = stepForces_, w.averageImpulse_ = averageImpulse_, w.averageTime_ = averageTime_;
  w.contactWork_ = contactWork_, w.externalWork_ = externalWork_, w.externalImpulse_ = externalImpulse_;
  w.removed_ = std::move(removed_);
  if (w.removed_.size() < w.model_->bodies.size()) w.removed_.resize(w.model_->bodies.size());
  *this = std::move(w);
}

void World::recordRemoval(size_t body, const RemovedMaterial& removed) {
  if (body >= model_->bodies.size())
    throw std::out_of_range("World::recordRemoval: body " + std::to_string(body) + " of " +
                            std::to_string(model_->bodies.size()));
  if (removed_.size() < model_->bodies.size()) removed_.resize(model_->bodies.size());
  RemovedMaterial& r = removed_[body];
  r.voxels += removed.voxels, r.volume += removed.volume, r.mass += removed.mass, r.momentum += removed.momentum;
}

}  // namespace gradel
