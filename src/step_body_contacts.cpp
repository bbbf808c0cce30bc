// The body-contact stage of World::step (body_contacts.h) and its glue: the start of the step it
// reads, the per-body motion the explicit pass measured, the inverse masses, the obstacles'
// wall re-pass of the vertices it moved (booked in the force ledger), and the pair constraints
// the frame-size integrators hand their solve (projective.h) with their warm start.
#include <algorithm>

#include "body_contact_energy.h"
#include "step_context.h"

namespace gradel {

// Soft-soft contact (body_contacts.h): the bodies' vertices at the start of the step, what the
// stage reads as the step's start (the boundary's swept band and the bounce; every vertex of a
// body for the last resort, which takes bodies back towards where they were).
void World::saveBodyContactStart() {
  for (const ContactBody& b : bodyContacts_->bodies())
    for (uint32_t u = b.vertexBegin; u < b.vertexEnd; ++u)
      bodyContactStartX_[u] = state_.positions[u], bodyContactStartV_[u] = state_.velocities[u];
}

// After the step (and its pins, which the stage leaves in place: inverse mass 0); the narrow phase
// on the step's thread team, the rest serially: the result does not depend on the thread count. Walls go last for every
// vertex the stage moved, so no vertex leaves the box (contacts.h; inelastic, as a vertex pinched between two
// surfaces).
void World::stageBodyContacts() {
  Vec3* x = state_.positions.data();
  Vec3* v = state_.velocities.data();
  // On the team when the step's own stages run on it (the governor: one thread is not faster now).
  const bool team = team_ && teamMembers_ > 1 && !(governor_ && governor_->usingOne());
  bodyContacts_->setTeam(team ? team_.get() : nullptr);
  // An explicit step measured the bodies' motion in its vertex pass, per block (stageVertices):
  // per body, its blocks, and again here the blocks that hold vertices of several bodies or a
  // pinned vertex (set after the pass).
  const BodyMotion* motion = nullptr;
  if (bodyMotionMeasured_) {
    const size_t B = bodyContacts_->bodies().size(), V = model_->numVertices();
    const RefPoint* ref = bodyContacts_->referencePositions();
    bodyMotion_.assign(B, BodyMotion{});
    for (size_t k = 0; k < bodyMotionBlockBody_.size(); ++k) {
      const uint32_t body = bodyMotionBlockBody_[k];
      if (body < B) {
        bodyMotion_[body].add(bodyMotionBlock_[k]);
      } else if (body == kMixedBlock) {
        for (size_t c = 0; c < B; ++c) {
          const ContactBody& cb = bodyContacts_->bodies()[c];
          const size_t begin = std::max<size_t>(k * kVertexBlock, cb.vertexBegin);
          const size_t end = std::min<size_t>({(k + 1) * kVertexBlock, V, cb.vertexEnd});
          if (begin < end) addMotion(x, bodyContactStartX_.data(), ref, begin, end, bodyMotion_[c]);
        }
      }
    }
    motion = bodyMotion_.data();
    bodyMotionMeasured_ = false;
  }
  bodyContactStats_ = bodyContacts_->resolve(
      {x, v, bodyContactStartX_.data(), bodyContactStartV_.data(), bodyContactInvMass_.data(), motion, dt_,
       sim_.integrator == IntegratorKind::SymplecticEuler});
  // The stage never adds energy (body_contact_energy.h): explicit steps the last resort left alone
  // (it moves whole bodies, which the touched list does not hold).
  if (sim_.integrator == IntegratorKind::SymplecticEuler && bodyContactStats_.takeBacks == 0 &&
      !bodyContacts_->touched().empty()) {
    if (!contactEnergy_) contactEnergy_ = std::make_unique<ContactEnergyLimiter>();
    ContactEnergyInput in;
    in.touched = &bodyContacts_->touched();
    in.startPositions = &bodyContacts_->touchedStart();
    in.startVelocities = &bodyContacts_->touchedStartVelocity();
    in.contacts = &bodyContacts_->contacts();
    in.rotations = state_.rotations.data();
    in.movable = bodyContactInvMass_.data();
    in.gravity = sim_.gravity;
    in.dt = dt_;
    const ContactEnergyCap cap = contactEnergy_->apply(*model_, in, x, v);
    bodyContactStats_.energyExcess = cap.excess, bodyContactStats_.energyRemoved = cap.removed;
  }
  scratch_->maxContactDepth = std::max(scratch_->maxContactDepth, bodyContactStats_.maxDepth);
  if (!domain_.enabled || bodyContacts_->contacts().empty()) return;
  // The vertices the stage moved: its contacts' vertices and face corners, each once (touched()).
  std::vector<uint32_t> moved = bodyContacts_->touched();
  std::sort(moved.begin(), moved.end());
  const size_t K = manipulators_.size();
  for (uint32_t u : moved) {
    if (bodyContactInvMass_[u] == 0) continue;
    const StepStart start{bodyContactStartV_[u], dt_, sim_.integrator == IntegratorKind::SymplecticEuler};
    Vec3 wallDv[kWalls] = {Vec3::Zero(), Vec3::Zero(), Vec3::Zero(), Vec3::Zero(), Vec3::Zero(), Vec3::Zero()};
    resolveDomain(domain_, bodyContactStartX_[u], x[u], v[u], model_->dim, false, &start, wallDv);
    // The walls' impulses go into the step's force ledger (closed after this stage, World::step).
    for (int wall = 0; wall < kWalls; ++wall)
      if (wallDv[wall] != Vec3::Zero()) {
        addImpulse(scratch_->impulse[K + size_t(wall)], model_->mass[u] * wallDv[wall], x[u], Vec3::Zero());
        scratch_->work += model_->mass[u] * wallDv[wall].dot(wallVelocity_[size_t(wall)]);
      }
  }
}

// Frame-size integrators: the search band of body contacts, the largest voxel size of the bodies.
Real World::bodyContactMargin() const {
  Real margin = 0;
  for (const ContactBody& b : bodyContacts_->bodies()) margin = std::max(margin, b.thickness);
  return margin;
}

// The body contacts as pair constraints of the implicit solve (projective.h), from the boundary
// vertices within `margin` of another body at positions x, each warm-started with the multiplier
// its vertex had against the same body in the last step. `keys` gets (vertex << 32 | face's body)
// per pair.
std::vector<PairConstraint> World::bodyPairConstraints(const std::vector<Vec3>& x, Real margin,
                                                       std::vector<uint64_t>& keys) {
  std::vector<BodyContacts::Proximity> near;
  bodyContacts_->proximity(x.data(), margin, near);
  std::vector<PairConstraint> pairs;
  keys.clear();
  for (const BodyContacts::Proximity& c : near) {
    const Real lambda = bodyContacts_->cache().multiplier(c.vertex, c.faceBody);
    const Real gap = kPairGap * bodyContacts_->bodies()[c.faceBody].thickness;
    pairs.push_back({c.vertex, c.face, c.w, c.n, gap, lambda});
    keys.push_back(BodyContacts::Cache::key(c.vertex, c.faceBody));
  }
  return pairs;
}

void World::keepBodyPairLambdas(const std::vector<PairConstraint>& pairs, const std::vector<uint64_t>& keys) {
  if (!bodyContacts_) return;
  std::vector<Real> lambdas(pairs.size());
  for (size_t j = 0; j < pairs.size(); ++j) lambdas[j] = pairs[j].lambda;
  bodyContacts_->cache().keepMultipliers(keys, lambdas);
}

void World::clearBodyPairLambdas() {
  if (bodyContacts_) bodyContacts_->cache().multipliers.clear();
}

// The large step's broad phase for the bodies: the boxes of their boundary vertices over the
// step (start and free-flight end), grown by the bodies' voxel size, overlap.
bool World::bodyContactsMayTouch() const {
  if (!bodyContactsOn()) return false;
  std::vector<Vec3> end(state_.positions.size());
  for (const ContactBody& b : bodyContacts_->bodies())
    for (uint32_t u : b.vertices)
      end[u] = freeFlight(state_.positions[u], state_.velocities[u], dt_, 0.5, sim_.gravity);
  return bodyContacts_->mayTouch(state_.positions.data(), end.data(), bodyContactMargin());
}

void World::setBodyContacts(std::vector<ContactBody> bodies, const BodyContactSettings& settings) {
  if (model_->dim != 3 && !bodies.empty()) throw InputError("body_contact: contact between bodies needs 3D bodies");
  for (const ContactBody& b : bodies)
    if (b.vertexEnd > model_->numVertices() || b.vertexBegin > b.vertexEnd)
      throw std::invalid_argument("World::setBodyContacts: a body's vertices lie outside the model");
  auto c = std::make_unique<BodyContacts>(std::move(bodies), settings);
  if (c->empty()) {
    bodyContacts_.reset();
    return;
  }
  bodyContacts_ = std::move(c);
  bodyContactStartX_ = state_.positions, bodyContactStartV_ = state_.velocities;
  updateBodyContactInvMass();
}

// The inverse masses the stage uses: the model's, 0 for pinned vertices (immovable); and per
// block of the vertex pass, the body whose vertices it holds (BodyMotion): one, none (B), or
// kMixedBlock (several bodies' vertices, or a pinned one: measured after the pins).
void World::updateBodyContactInvMass() {
  if (!bodyContacts_) return;
  bodyContactInvMass_ = model_->invMass;
  for (uint32_t u : pinSet_.vertices) bodyContactInvMass_[u] = 0;
  const size_t V = model_->numVertices(), blocks = (V + kVertexBlock - 1) / kVertexBlock;
  const std::vector<ContactBody>& bodies = bodyContacts_->bodies();
  const uint32_t B = uint32_t(bodies.size());
  bodyMotionBlock_.assign(blocks, BodyMotion{});
  bodyMotionBlockBody_.assign(blocks, B);
  for (uint32_t c = 0; c < B; ++c)
    for (size_t k = bodies[c].vertexBegin / kVertexBlock; k * kVertexBlock < bodies[c].vertexEnd; ++k) {
      uint32_t& body = bodyMotionBlockBody_[k];
      const bool whole =
          k * kVertexBlock >= bodies[c].vertexBegin && std::min(V, (k + 1) * kVertexBlock) <= bodies[c].vertexEnd;
      body = body == B && whole ? c : kMixedBlock;
    }
  for (uint32_t u : pinSet_.vertices) bodyMotionBlockBody_[u / kVertexBlock] = kMixedBlock;
  bodyMotionMeasured_ = false;
}

}  // namespace gradel
