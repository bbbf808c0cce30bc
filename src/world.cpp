// World: creation (dt and its rule, damping, the rest data's derived arrays), the step as its
// list of stages (step_context.h), pins, external forces and the state's hash. The stages live
// in step_*.cpp, the figures in world_metrics.cpp, the start overlaps' release in
// start_overlap_release.cpp, the integrator names and "auto" in integrator_choice.cpp.
#include "gradel/world.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "element_stage.h"
#include "gradel/contact_work.h"
#include "gradel/settings_check.h"
#include "gradel/stability.h"
#include "huge_pages.h"
#include "plane.h"
#include "body_contact_energy.h"
#include "step_context.h"
#include "thread_team.h"

namespace gradel {

namespace {
// A model made by hand without RestModel::bodies is one body.
std::shared_ptr<const RestModel> withBodies(std::shared_ptr<const RestModel> model) {
  if (!model) throw std::invalid_argument("World: no model");
  if (!model->bodies.empty()) return model;
  auto m = std::make_shared<RestModel>(*model);
  m->bodies.push_back(wholeModelBody(*m));
  return m;
}
}  // namespace


World::World(std::shared_ptr<const RestModel> model, const SimulationSettings& sim, const DomainSettings& domain,
             std::vector<ManipulatorSettings> manipulators)
    : World(std::move(model), sim, domain, std::move(manipulators), nullptr) {}

World::World(std::shared_ptr<const RestModel> model, const SimulationSettings& sim, const DomainSettings& domain,
             std::vector<ManipulatorSettings> manipulators, const FrequencyEstimate* frequency)
    : model_(withBodies(std::move(model))), stageRest_(std::make_unique<const ElementStageRest>(*model_)), sim_(sim),
      domain_(domain), scratch_(std::make_unique<StepContext>()) {
  if (sim_.dtFraction == 0) sim_.dtFraction = defaultDtFraction(sim_.dtPeriod);
  validate(sim_);
  validate(domain_, model_->dim);
  sim_.gravity = projectToPlane(sim_.gravity, model_->dim);  // a 2D body moves in its plane (plane.h)
  // Damping: one rate unless the regions' rates differ between vertices (model.h).
  const RestModel& rm = *model_;
  uniformDamping_ = rm.vertexDamping(0, sim_.damping);
  Real minDamping = uniformDamping_;
  bool uniform = true;
  for (size_t i = 1; rm.hasRegionDamping() && i < rm.numVertices(); ++i) {
    const Real c = rm.vertexDamping(i, sim_.damping);
    uniform = uniform && c == uniformDamping_, minDamping = std::min(minDamping, c);
  }
  Real period = sim_.dtPeriod == PeriodRule::Element ? model_->smallestPeriod : model_->smallestVertexPeriod;
  if (sim_.dtPeriod == PeriodRule::Operator) {
    // The body's own fastest vibration (stability.h); a model without elements keeps the vertex bound.
    // A world with a carving tool keeps the Ritz vector: its first event is warm started too
    // (stability_warm.h; the estimate's bits are the same).
    const bool carving = std::any_of(manipulators.begin(), manipulators.end(), [](const ManipulatorSettings& s) {
      return s.carve || s.shape == ManipulatorShape::Blade;
    });
    std::unique_ptr<ThreadTeam> team;  // the same bits at any thread count
    frequency_ = frequency ? *frequency : highestFrequency(*model_, 48, carving ? &ritz_ : nullptr, estimateTeam(team));
    if (frequency_.omega > 0) period = 2 * M_PI / frequency_.omega;
  }
  // The implicit integrator is stable at any dt: "auto" is one display frame.
  if (sim_.integrator == IntegratorKind::Auto) chooseIntegrator(period);
  const bool frameStep = sim_.integrator == IntegratorKind::Implicit || sim_.integrator == IntegratorKind::LargeStep;
  Real autoDt = frameStep ? 1.0 / 60.0 : sim_.dtFraction * period;
  if (sim_.integrator == IntegratorKind::ForwardEuler && sim_.dt == 0) {
    // Forward Euler on x'' = -w^2 x with the velocity damping v <- v / (1 + c dt) multiplies the
    // energy of a mode by (1 + (w dt)^2) / (1 + c dt) every step: unstable at every dt without
    // damping, stable for dt < c / w^2. With w = 2 pi / period (the fastest mode), half that bound
    // (validate() has refused c = 0).
    const Real omega = 2 * M_PI / period;
    // The least damped vertex (regions' rates, model.h) bounds it.
    autoDt = std::min(autoDt, 0.5 * minDamping / (omega * omega));
  }
  dt_ = sim_.dt > 0 ? sim_.dt : autoDt;
  if (!(dt_ > 0) || !std::isfinite(dt_)) throw InputError("dt: could not derive a positive time step");
  {
    char buf[200];
    if (sim_.dt > 0)
      std::snprintf(buf, sizeof buf, "given");
    else if (frameStep)
      std::snprintf(buf, sizeof buf, "one frame (1/60 s)");
    else if (sim_.dtPeriod == PeriodRule::Operator && frequency_.omega > 0)
      std::snprintf(buf, sizeof buf, "operator x %.3g: 2 pi / omega_max, omega_max %.4g rad/s", sim_.dtFraction,
                    frequency_.omega);
    else
      std::snprintf(buf, sizeof buf, "%s x %.3g: %s", periodRuleName(sim_.dtPeriod), sim_.dtFraction,
                    sim_.dtPeriod == PeriodRule::Element ? "the smallest element's period (the paper's rule)"
                                                         : "the stiffest vertex's period");
    dtRule_ = buf;
    if (sim_.integrator == IntegratorKind::ForwardEuler && sim_.dt == 0 && dt_ < sim_.dtFraction * period)
      dtRule_ += " (forward Euler: capped at damping / (2 omega^2))";
  }
  if (!uniform) {
    vertexDampFactor_.resize(rm.numVertices());
    for (size_t i = 0; i < rm.numVertices(); ++i)
      vertexDampFactor_[i] = dampingFactor(rm.vertexDamping(i, sim_.damping), dt_);
  }

  const size_t V = model_->numVertices(), E = model_->numElements();
  state_.positions = model_->restPositions;
  state_.velocities.assign(V, Vec3::Zero());
  state_.rotations.assign(E, Quat::Identity());
  scratch_->frames.resize(E);
  // The arrays the explicit step walks every step: 2 MiB pages for large bodies.
  const RestModel& m = *model_;
  adviseHugePages(state_.positions), adviseHugePages(state_.velocities), adviseHugePages(m.restPositions);
  adviseHugePages(state_.rotations), adviseHugePages(scratch_->frames), adviseHugePages(m.invMass);
  adviseHugePages(m.elemVerts), adviseHugePages(m.elemStart), adviseHugePages(m.stiffness),
      adviseHugePages(m.restCentroids);
  adviseHugePages(stageRest_->vertexFrames), adviseHugePages(stageRest_->vertexCount);
  adviseHugePages(stageRest_->groups), adviseHugePages(stageRest_->lattice8), adviseHugePages(stageRest_->lattice16);

  vertexStiffness_ = vertexStiffness(m);  // the contacts' work (contact_work.h)
  for (ManipulatorSettings& s : manipulators) addManipulator(std::move(s));
}

World::World(std::shared_ptr<const RestModel> model, WorldSettings settings, std::vector<ContactBody> contactBodies)
    : World(std::move(model), settings.simulation, settings.domain, std::move(settings.manipulators)) {
  const std::vector<Vec3>& v0 = settings.bodyVelocities;
  if (!v0.empty() && v0.size() != model_->bodies.size())
    throw std::invalid_argument("World: " + std::to_string(v0.size()) + " body velocities for " +
                                std::to_string(model_->bodies.size()) + " bodies");
  for (size_t i = 0; i < v0.size(); ++i)
    if (!v0[i].allFinite()) throw InputError("bodies[" + std::to_string(i) + "].velocity: not a finite vector");
  if (!settings.pins.empty()) setPins(std::move(settings.pins));
  bodyContactSettings_ = settings.bodyContact;
  if (!contactBodies.empty()) setBodyContacts(std::move(contactBodies), settings.bodyContact);
  if (settings.releaseStartOverlaps) releaseStartOverlaps();
  for (size_t i = 0; i < v0.size(); ++i) {
    const Vec3 v = projectToPlane(v0[i], model_->dim);  // a 2D body moves in its plane
    const BodyRange& r = model_->bodies[i];
    std::fill(state_.velocities.begin() + r.vertexBegin, state_.velocities.begin() + r.vertexEnd, v);
  }
}

World::~World() = default;
World::World(World&&) noexcept = default;
World& World::operator=(World&&) noexcept = default;

size_t World::addManipulator(ManipulatorSettings s, const Vec3& position) {
  validate(s);
  if (s.shape == ManipulatorShape::Cylinder || s.shape == ManipulatorShape::Blade) s.axis.normalize();
  if (s.shape == ManipulatorShape::Blade) s.widthAxis.normalize();
  projectToPlane(s.path, model_->dim);  // 2D: the pose in the plane from here on (plane.h)
  Manipulator m;
  m.settings = std::move(s);
  const bool scripted = !m.settings.path.keys.empty();
  m.position = scripted ? m.settings.path.position(state_.time) : projectToPlane(position, model_->dim);
  m.velocity = scripted ? m.settings.path.velocity(state_.time) : Vec3::Zero();
  m.previousPosition = m.position;  // no sweep from elsewhere on its first step
  manipulators_.push_back(std::move(m));
  stepForces_.manipulators.resize(manipulators_.size());  // no force on it before its first step
  averageImpulse_.manipulators.resize(manipulators_.size());
  return manipulators_.size() - 1;
}

void World::setManipulatorPose(size_t i, const Vec3& position, const Vec3& velocity) {
  Manipulator& m = manipulators_.at(i);
  m.position = projectToPlane(position, model_->dim);  // previousPosition keeps the last step's pose: the sweep covers the jump
  m.velocity = projectToPlane(velocity, model_->dim);
}

// The step as its list of stages (step_context.h).
void World::step() {
  beginStep();
  advanceIntegrator();                           // ... and the pins
  if (scratch_->bodyContacts) stageBodyContacts();  // broad -> narrow -> response, the walls' re-pass
  finishContactImpulses();                       // the ledger closes last
}

// Begin: the start overlaps' release, the external forces' impulse (the same before every
// integrator), the step's constants (StepContext) and the force ledger opened.
void World::beginStep() {
  if (separatingStartOverlaps()) {
    advanceStartOverlapRelease();
  } else {
    wallVelocity_.fill(Vec3::Zero());
    manipulatorGrowth_.clear();
  }
  if (!externalForce_.empty()) {  // external_force.h
    const ExternalImpulse e =
        applyExternalImpulses(externalForce_, model_->mass, pinSet_.vertices, dt_, state_.velocities);
    externalImpulse_ += e.impulse;
    externalWork_ += std::max(Real(0), e.work);
    if (largeStep_) largeStep_->resetEnergyBudget();  // the forces did work
  }
  StepContext& c = *scratch_;
  c.dt = dt_, c.tNext = state_.time + dt_;
  c.gravity = sim_.gravity;  // projected into a 2D body's plane by the constructor
  c.obstacles = !manipulators_.empty() || domain_.enabled;
  c.bodyContacts = bodyContactsOn();
  c.symplectic = sim_.integrator == IntegratorKind::SymplecticEuler;
  beginContactImpulses();
}

// The integrator's advance, dispatched once per step. (The explicit integrators keep the body
// contacts' start in their vertex pass, stageVertices.)
void World::advanceIntegrator() {
  const bool frameStep = sim_.integrator == IntegratorKind::Implicit || sim_.integrator == IntegratorKind::LargeStep;
  if (scratch_->bodyContacts && frameStep) saveBodyContactStart();
  if (sim_.integrator == IntegratorKind::Implicit)
    stepImplicit(false);
  else if (sim_.integrator == IntegratorKind::LargeStep)
    stepLargeStep();
  else
    stepExplicit();
}

void World::advanceTo(Real t) {
  while (state_.time + 0.5 * dt_ < t) step();
}

void World::setPins(std::vector<PinSettings> pins) {
  std::vector<std::array<uint32_t, 2>> bodies;
  for (const BodyRange& b : model_->bodies) bodies.push_back({b.vertexBegin, b.vertexEnd});
  pinSet_ = selectPins(pins, model_->restPositions, bodies);
  for (PinSettings& p : pins) projectToPlane(p.path, model_->dim);  // 2D: offsets in the plane (plane.h)
  pins_ = std::move(pins);
  updateBodyContactInvMass();
  projective_.reset(), largeStep_.reset();  // the implicit systems eliminate the pinned vertices: refactor
  applyPins(state_.time);
}

void World::addExternalForces(const std::vector<uint32_t>& vertices, const std::vector<Vec3>& forces) {
  if (vertices.size() != forces.size())
    throw InputError("forces: " + std::to_string(forces.size()) + " forces for " + std::to_string(vertices.size()) +
                     " vertices (expected one per vertex)");
  const size_t n = model_->numVertices();
  for (size_t k = 0; k < vertices.size(); ++k) {
    if (vertices[k] >= n)
      throw InputError("vertices: " + std::to_string(vertices[k]) + " is not a vertex (expected 0.." +
                       std::to_string(n - 1) + ")");
    if (!forces[k].allFinite()) throw InputError("forces: entry " + std::to_string(k) + " is not finite");
  }
  if (externalForce_.empty()) externalForce_.assign(n, Vec3::Zero());
  for (size_t k = 0; k < vertices.size(); ++k) externalForce_[vertices[k]] += projectToPlane(forces[k], model_->dim);
}

std::vector<Vec3> World::pinTargets(Real t) const {
  std::vector<Vec3> x(pinSet_.vertices.size());
  for (size_t j = 0; j < x.size(); ++j)
    x[j] = model_->restPositions[pinSet_.vertices[j]] + pins_[pinSet_.pinOf[j]].path.position(t);
  return x;
}

// Pinned vertices take their prescribed position and the path's velocity (explicit integrators:
// after the step, so pins override forces and contacts).
void World::applyPins(Real t) {
  const std::vector<Vec3> x = pinTargets(t);
  for (size_t j = 0; j < x.size(); ++j) {
    const uint32_t i = pinSet_.vertices[j];
    state_.positions[i] = x[j];
    state_.velocities[i] = pins_[pinSet_.pinOf[j]].path.velocity(t);  // in a 2D body's plane: setPins
  }
}

uint64_t World::stateHash() const {
  uint64_t h = 1469598103934665603ull;
  auto mix = [&](const void* data, size_t bytes) {
    const unsigned char* p = static_cast<const unsigned char*>(data);
    for (size_t i = 0; i < bytes; ++i) h = (h ^ p[i]) * 1099511628211ull;
  };
  mix(state_.positions.data(), state_.positions.size() * sizeof(Vec3));
  mix(state_.velocities.data(), state_.velocities.size() * sizeof(Vec3));
  return h;
}

size_t World::memoryBytes() const {
  auto bytes = [](const auto& v) { return v.capacity() * sizeof(v[0]); };
  size_t b = sizeof(*this) + model_->memoryBytes() + stageRest_->memoryBytes();
  b += bytes(state_.positions) + bytes(state_.velocities) + bytes(state_.rotations);
  b += bytes(scratch_->frames) + bytes(scratch_->previousPositions) + bytes(scratch_->previousVelocities) +
       bytes(scratch_->contactDepth) + bytes(scratch_->impulse) + bytes(scratch_->contactSurface);
  for (const StepContext::TouchedBlocks& t : scratch_->touched) b += bytes(t.block) + bytes(t.work) + bytes(t.impulse);
  b += (elementSplit_.capacity() + vertexSplit_.capacity()) * sizeof(size_t) +
       elementChunks_.capacity() * sizeof(elementChunks_[0]);
  for (const Manipulator& m : manipulators_) b += sizeof(m) + bytes(m.settings.path.keys);
  b += bytes(bodyContactStartX_) + bytes(bodyContactStartV_) + bytes(bodyContactInvMass_);
  if (bodyContacts_)
    for (const ContactBody& c : bodyContacts_->bodies())
      b += bytes(c.vertices) + bytes(c.triangles) + bytes(c.vertexTriStart) + bytes(c.vertexTris) + bytes(c.nearStart) +
           bytes(c.near);
  return b;
}

}  // namespace gradel
