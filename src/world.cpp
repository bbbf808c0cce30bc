#include "gradel/world.h"

#include <cmath>
#include <cstring>

#include "gradel/element.h"

namespace gradel {

IntegratorKind parseIntegratorKind(const std::string& name) {
  if (name == "symplectic") return IntegratorKind::SymplecticEuler;
  if (name == "forward_euler") return IntegratorKind::ForwardEuler;
  throw InputError("unknown integrator '" + name + "' (expected symplectic or forward_euler)");
}

const char* integratorKindName(IntegratorKind k) {
  return k == IntegratorKind::ForwardEuler ? "forward_euler" : "symplectic";
}

PeriodRule parsePeriodRule(const std::string& name) {
  if (name == "vertex") return PeriodRule::Vertex;
  if (name == "element") return PeriodRule::Element;
  throw InputError("unknown period rule '" + name + "' (expected vertex or element)");
}

const char* periodRuleName(PeriodRule r) { return r == PeriodRule::Element ? "element" : "vertex"; }

World::World(std::shared_ptr<const RestModel> model, const SimulationSettings& sim, const DomainSettings& domain,
             std::vector<ManipulatorSettings> manipulators)
    : model_(std::move(model)), sim_(sim), domain_(domain) {
  if (!model_) throw std::invalid_argument("World: no model");
  if (sim_.threads < 1) sim_.threads = 1;
  if (!(sim_.dt >= 0) || !std::isfinite(sim_.dt)) throw InputError("simulation.dt must be 'auto' or a positive number of seconds");
  if (!(sim_.dtFraction > 0 && sim_.dtFraction <= 1)) throw InputError("simulation.dt_fraction must be in (0, 1]");
  if (!(sim_.damping >= 0) || !std::isfinite(sim_.damping)) throw InputError("simulation.damping must be >= 0");
  if (!sim_.gravity.allFinite()) throw InputError("simulation.gravity must be finite");
  const Real period = sim_.dtPeriod == PeriodRule::Element ? model_->smallestPeriod : model_->smallestVertexPeriod;
  dt_ = sim_.dt > 0 ? sim_.dt : sim_.dtFraction * period;
  if (!(dt_ > 0) || !std::isfinite(dt_)) throw InputError("simulation.dt: could not derive a positive time step");

  const size_t V = model_->numVertices(), E = model_->numElements(), P = model_->numPairs();
  state_.positions = model_->restPositions;
  state_.velocities.assign(V, Vec3::Zero());
  state_.rotations.assign(E, Quat::Identity());
  scratch_.pairForces.assign(P, Vec3::Zero());
  scratch_.elementEnergy.assign(E, 0.0);
  scratch_.contactDepth.assign(V, 0.0);

  for (ManipulatorSettings& s : manipulators) {
    Manipulator m;
    if (s.shape == ManipulatorShape::Cylinder) {
      if (!(s.axis.norm() > 0)) throw InputError("manipulator axis must be non-zero");
      s.axis.normalize();
    }
    m.settings = std::move(s);
    m.position = m.settings.path.position(0.0);
    m.velocity = m.settings.path.velocity(0.0);
    m.previousPosition = m.position;
    manipulators_.push_back(std::move(m));
  }
}

void World::setManipulatorPose(size_t i, const Vec3& position, const Vec3& velocity) {
  Manipulator& m = manipulators_.at(i);
  m.position = position;  // previousPosition keeps the pose of the last step: the sweep covers the jump
  m.velocity = velocity;
}

// Stage 1: elastic forces per element into per-pair slots (no two elements write the same slot).
void World::stageElementForces(size_t begin, size_t end) {
  const RestModel& m = *model_;
  const Vec3* x = state_.positions.data();
  for (size_t e = begin; e < end; ++e) {
    const uint32_t b = m.elemStart[e], n = m.elemStart[e + 1] - b;
    const ElementResult r = elementForces(m.dim, x, &m.elemVerts[b], &m.restOffsets[b], int(n), m.stiffness[e],
                                          state_.rotations[e], &scratch_.pairForces[b], sim_.rotationIterations);
    scratch_.elementEnergy[e] = r.energy;
  }
}

// Stage 2: gather each vertex's pair forces in a fixed order, then integrate (eqs. 2-3).
void World::stageIntegrate(size_t begin, size_t end) {
  const RestModel& m = *model_;
  const Real dt = dt_;
  const Real damp = 1.0 / (1.0 + sim_.damping * dt);
  const bool forward = sim_.integrator == IntegratorKind::ForwardEuler;
  Vec3 g = sim_.gravity;
  if (m.dim == 2) g.z() = 0;
  for (size_t i = begin; i < end; ++i) {
    Vec3 f = Vec3::Zero();
    for (uint32_t q = m.vertPairStart[i]; q < m.vertPairStart[i + 1]; ++q) f += scratch_.pairForces[m.vertPairs[q]];
    const Vec3 a = f * m.invMass[i] + g;
    Vec3& x = state_.positions[i];
    Vec3& v = state_.velocities[i];
    if (forward) {
      x += dt * v;  // eq. 3 with V(T): the paper's literal order
      v = (v + dt * a) * damp;
    } else {
      v = (v + dt * a) * damp;
      x += dt * v;  // symplectic: P(T+dT) = P(T) + V(T+dT) dT
    }
  }
}

// Stage 3: contacts, per vertex (independent). The first pass bounces (sec. 3.5). A vertex
// pinched between surfaces (a manipulator and a wall, or two manipulators) is resolved again, up
// to three more passes, inelastically: repeated elastic reflections between two surfaces would
// pump energy into it. The walls go last in every pass, so no vertex ever leaves the box.
void World::stageContacts(size_t begin, size_t end) {
  const int dim = model_->dim;
  const size_t surfaces = manipulators_.size() + (domain_.enabled ? 1 : 0);
  for (size_t i = begin; i < end; ++i) {
    Vec3& x = state_.positions[i];
    Vec3& v = state_.velocities[i];
    Real depth = 0;
    for (int pass = 0; pass < 4; ++pass) {
      const bool bounce = pass == 0;
      Real passDepth = 0;
      for (const Manipulator& mp : manipulators_)
        passDepth = std::max(passDepth, resolveManipulator(mp, scratch_.previousPositions[i], x, v, dim, bounce).depth);
      passDepth = std::max(passDepth, resolveDomain(domain_, scratch_.previousPositions[i], x, v, dim, bounce).depth);
      depth = std::max(depth, passDepth);
      if (passDepth == 0 || surfaces < 2) break;
    }
    scratch_.contactDepth[i] = depth;
  }
}

void World::moveManipulators(Real tNext) {
  for (Manipulator& m : manipulators_) {
    if (m.settings.path.keys.empty()) continue;  // posed from outside
    m.position = m.settings.path.position(tNext);
    m.velocity = m.settings.path.velocity(tNext);
  }
}

namespace {
// Runs fn(begin, end) over [0, n) split into `threads` contiguous ranges. Each index is handled
// by exactly one call and no result depends on the split, so any thread count gives the same
// answer bit for bit.
template <class Fn>
void parallelRanges(size_t n, int threads, Fn&& fn) {
  if (threads <= 1 || n < 1024) {
    fn(size_t(0), n);
    return;
  }
  const size_t chunks = size_t(threads) * 8;
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads)
  for (size_t c = 0; c < chunks; ++c) fn(n * c / chunks, n * (c + 1) / chunks);
}
}  // namespace

void World::step() {
  const size_t V = model_->numVertices(), E = model_->numElements();
  const bool contacts = !manipulators_.empty() || domain_.enabled;
  if (contacts) scratch_.previousPositions = state_.positions;
  parallelRanges(E, sim_.threads, [&](size_t b, size_t e) { stageElementForces(b, e); });
  parallelRanges(V, sim_.threads, [&](size_t b, size_t e) { stageIntegrate(b, e); });
  moveManipulators(state_.time + dt_);
  if (contacts) parallelRanges(V, sim_.threads, [&](size_t b, size_t e) { stageContacts(b, e); });
  for (Manipulator& m : manipulators_) m.previousPosition = m.position;
  state_.time += dt_;
}

void World::advanceTo(Real t) {
  while (state_.time + 0.5 * dt_ < t) step();
}

std::vector<Real> World::elementStress() const {
  const RestModel& m = *model_;
  std::vector<Real> s(m.numElements());
  std::vector<Vec3> f;
  for (size_t e = 0; e < m.numElements(); ++e) {
    const uint32_t b = m.elemStart[e], n = m.elemStart[e + 1] - b;
    f.resize(n);
    Quat q = state_.rotations[e];
    const ElementResult r = elementForces(m.dim, state_.positions.data(), &m.elemVerts[b], &m.restOffsets[b], int(n),
                                          m.stiffness[e], q, f.data(), 20);
    s[e] = std::sqrt(r.sumSqDisp / n) / m.size[e];
  }
  return s;
}

std::vector<Real> World::vertexStress() const {
  const RestModel& m = *model_;
  const std::vector<Real> es = elementStress();
  // Element of each pair, for the gather.
  std::vector<uint32_t> pairElem(m.numPairs());
  for (size_t e = 0; e < m.numElements(); ++e)
    for (uint32_t p = m.elemStart[e]; p < m.elemStart[e + 1]; ++p) pairElem[p] = uint32_t(e);
  std::vector<Real> vs(m.numVertices(), 0.0);
  for (size_t i = 0; i < m.numVertices(); ++i) {
    const uint32_t b = m.vertPairStart[i], n = m.vertPairStart[i + 1] - b;
    Real sum = 0;
    for (uint32_t q = b; q < b + n; ++q) sum += es[pairElem[m.vertPairs[q]]];
    vs[i] = n ? sum / n : 0;
  }
  return vs;
}

Metrics World::metrics() const {
  const RestModel& m = *model_;
  Metrics r;
  r.time = state_.time;
  Vec3 g = sim_.gravity;
  if (m.dim == 2) g.z() = 0;

  // Elastic forces and energy at the current positions.
  std::vector<Vec3> pairForces(m.numPairs());
  r.minElementDet = std::numeric_limits<Real>::infinity();
  for (size_t e = 0; e < m.numElements(); ++e) {
    const uint32_t b = m.elemStart[e], n = m.elemStart[e + 1] - b;
    Quat q = state_.rotations[e];
    const ElementResult er = elementForces(m.dim, state_.positions.data(), &m.elemVerts[b], &m.restOffsets[b], int(n),
                                           m.stiffness[e], q, &pairForces[b], 20);
    r.elasticEnergy += er.energy;
    r.maxStress = std::max(r.maxStress, std::sqrt(er.sumSqDisp / n) / m.size[e]);
    r.minElementDet = std::min(r.minElementDet,
                               elementDeterminant(m.dim, state_.positions.data(), &m.elemVerts[b], &m.restOffsets[b], int(n)));
  }

  // Symplectic Euler's stored velocity belongs half a step before its positions (it is the
  // leapfrog v_{n-1/2}); the kinetic energy at time t uses v + a(x) dt / 2, as Stormer-Verlet
  // does. This is what makes the measured energy of an undamped run flat to O(dt^2) rather
  // than swing by O(omega dt). Forward Euler's velocity is already synchronous.
  const bool staggered = sim_.integrator == IntegratorKind::SymplecticEuler;
  for (size_t i = 0; i < m.numVertices(); ++i) {
    const Vec3& x = state_.positions[i];
    Vec3 v = state_.velocities[i];
    if (staggered) {
      Vec3 f = Vec3::Zero();
      for (uint32_t q = m.vertPairStart[i]; q < m.vertPairStart[i + 1]; ++q) f += pairForces[m.vertPairs[q]];
      v += 0.5 * dt_ * (f * m.invMass[i] + g);
    }
    r.kineticEnergy += 0.5 * m.mass[i] * v.squaredNorm();
    r.gravityEnergy -= m.mass[i] * g.dot(x);
    r.linearMomentum += m.mass[i] * v;
    r.angularMomentum += m.mass[i] * x.cross(v);
    Real pen = 0;
    for (const Manipulator& mp : manipulators_) pen = std::max(pen, -mp.signedDistance(x, nullptr));
    if (domain_.enabled)
      for (int a = 0; a < m.dim; ++a) pen = std::max({pen, domain_.min[a] - x[a], x[a] - domain_.max[a]});
    r.maxPenetration = std::max(r.maxPenetration, pen);
    r.maxContactDepth = std::max(r.maxContactDepth, scratch_.contactDepth[i]);
  }
  return r;
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

}  // namespace gradel
