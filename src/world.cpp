#include "gradel/world.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <type_traits>
#ifdef GRADEL_WITH_OPENMP
#include <omp.h>
#endif

#include "element_stage.h"
#include "gradel/contact_work.h"
#include "gradel/overlaps.h"
#include "gradel/element.h"
#include "gradel/integration.h"
#include "gradel/rotation_fit.h"
#include "gradel/settings_check.h"
#include "gradel/stability.h"
#include "huge_pages.h"
#include "simd.h"
#include "thread_team.h"

namespace gradel {

/// Per-step scratch (never read across steps except for output).
struct World::StepScratch {
  std::vector<ElementFrame> frames;      ///< Per element: k M and (k e, k), written by the element stage.
  std::vector<Vec3> previousPositions;   ///< [m] positions at the start of an implicit step (swept contacts).
  std::vector<Vec3> previousVelocities;  ///< [m/s] velocities then (the bounce's crossing speed, contacts.h).
  std::vector<Real> contactDepth;        ///< [m] per vertex, implicit step only: depth before correction.
  Real maxContactDepth = 0;              ///< [m] deepest vertex found (and corrected) in the last step.
  // Contact impulses (World::stepContactForces): per surface (the manipulators, then each of the kWalls walls)
  // the impulse the contact response gave the body [N s] and its moment [N m s] (about the
  // manipulator's centre, the walls' about the origin). The explicit step sums them per aligned
  // block of kVertexBlock vertices (blockImpulse, blocks x surfaces; blockTouched marks the blocks
  // the broad phase let through) and adds the blocks in block order after the step: the same
  // sums at any thread count, and no work for the blocks no contact can reach.
  std::vector<ContactForce> impulse;
  std::vector<ContactForce> blockImpulse;
  std::vector<uint8_t> blockTouched;
  std::vector<int> contactSurface;  ///< Per vertex, implicit step: the surface that moved it last (-1: none).
  // The energy the contacts gave the bodies this step (contact_work.h): per block of the explicit
  // stage (added in block order by finishContactImpulses, with the impulses), and the step's sum.
  std::vector<Real> blockWork;
  Real work = 0;
};

namespace {
// The explicit vertex stage's blocks: the broad phase's unit and the contact forces' partial sums.
constexpr size_t kVertexBlock = 16;
// Pair constraints (body contacts in the implicit solve) hold a vertex this far [voxel size of
// the face's body] outside the face: the post-step stage (skin 1e-6) then has nothing to do.
constexpr Real kPairGap = 1e-4;
// One vertex's contact impulse J = m dv on the body from `surface` at x, about `centre` (2D: in the plane).
inline void addImpulse(ContactForce& acc, const Vec3& J, const Vec3& x, const Vec3& centre, int dim) {
  Vec3 r = x - centre;
  if (dim == 2) r.z() = 0;
  acc.force += J, acc.torque += r.cross(J);
}
}  // namespace

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

Real defaultDtFraction(PeriodRule r) { return r == PeriodRule::Operator ? 0.2 : 0.1; }
Real maxDtFraction(PeriodRule r) { return r == PeriodRule::Element ? 0.1 : 0.3; }

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
    : model_(withBodies(std::move(model))), stageRest_(std::make_unique<const ElementStageRest>(*model_)), sim_(sim),
      domain_(domain), scratch_(std::make_unique<StepScratch>()) {
  if (sim_.dtFraction == 0) sim_.dtFraction = defaultDtFraction(sim_.dtPeriod);
  validate(sim_);
  validate(domain_, model_->dim);
  if (model_->dim == 2) sim_.gravity.z() = 0;  // a 2D body moves in its plane: the one place gravity is projected
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
    frequency_ = highestFrequency(*model_);
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
  adviseHugePages(m.elemVerts), adviseHugePages(m.restOffsets), adviseHugePages(m.elemStart),
      adviseHugePages(m.stiffness);
  adviseHugePages(stageRest_->vertexFrames), adviseHugePages(stageRest_->vertexStart);
  adviseHugePages(stageRest_->elements), adviseHugePages(stageRest_->pairs);

  vertexStiffness_ = vertexStiffness(m);  // the contacts' work (contact_work.h)
  for (ManipulatorSettings& s : manipulators) addManipulator(std::move(s));
}

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

World::~World() = default;
World::World(World&&) noexcept = default;
World& World::operator=(World&&) noexcept = default;

size_t World::addManipulator(ManipulatorSettings s, const Vec3& position) {
  validate(s);
  if (s.shape == ManipulatorShape::Cylinder) s.axis.normalize();
  Manipulator m;
  m.settings = std::move(s);
  const bool scripted = !m.settings.path.keys.empty();
  m.position = scripted ? m.settings.path.position(state_.time) : position;
  m.velocity = scripted ? m.settings.path.velocity(state_.time) : Vec3::Zero();
  m.previousPosition = m.position;  // no sweep from elsewhere on its first step
  manipulators_.push_back(std::move(m));
  stepForces_.manipulators.resize(manipulators_.size());  // no force on it before its first step
  averageImpulse_.manipulators.resize(manipulators_.size());
  return manipulators_.size() - 1;
}

void World::setManipulatorPose(size_t i, const Vec3& position, const Vec3& velocity) {
  Manipulator& m = manipulators_.at(i);
  m.position = position;  // previousPosition keeps the pose of the last step: the sweep covers the jump
  m.velocity = velocity;
}

// Stage 1: the elements [begin, end): rotations fitted (eq. 1) and their frames (element_stage.h).
void World::stageElementFrames(size_t begin, size_t end) {
  computeElementFrames(*model_, *stageRest_, begin, end, state_.positions.data(), state_.rotations.data(),
                       scratch_->frames.data(), sim_.rotationIterations);
}

// Where contacts can happen this step (the broad phase of the vertex stage): each manipulator's
// swept bounds (its centre's box over the step, grown by the radius of a sphere around the
// shape) and the walls. A vertex whose whole step stays inside the walls and outside every swept
// bound cannot touch anything: resolveVertexContacts would leave it unchanged, so it is skipped
// (the results are bit for bit those of resolving every vertex).
struct World::ContactBounds {
  std::vector<simd::d4> lo, hi;  ///< Per manipulator: swept bounds grown by its radius.
  simd::d4 wallLo, wallHi;       ///< Inside the walls (infinite without walls).
};

World::ContactBounds World::contactBounds() const {
  using namespace simd;
  ContactBounds b;
  constexpr Real inf = std::numeric_limits<Real>::infinity();
  for (const Manipulator& m : manipulators_) {
    const ManipulatorSettings& s = m.settings;
    const Real reach = s.shape == ManipulatorShape::Cylinder ? std::hypot(s.radius, s.halfLength) : s.radius;
    const d4 p0 = loadVec3(m.previousPosition), p1 = loadVec3(m.position);
    // 2D: the manipulator's own z does not matter (contacts are in the plane), so neither does
    // the bound's z.
    // Lane 3 carries no coordinate: never a reason to skip.
    d4 grow = {reach, reach, model_->dim == 2 ? inf : reach, inf};
    b.lo.push_back(min(p0, p1) - grow), b.hi.push_back(max(p0, p1) + grow);
  }
  if (domain_.enabled) {
    b.wallLo = loadVec3(domain_.min), b.wallHi = loadVec3(domain_.max);
    if (model_->dim == 2) b.wallLo[2] = -inf, b.wallHi[2] = inf;  // resolveDomain ignores z in 2D
  } else {
    b.wallLo = splat(-inf), b.wallHi = splat(inf);
  }
  b.wallLo[3] = -inf, b.wallHi[3] = inf;
  return b;
}

// Stage 2, per vertex [begin, end): gather the elastic force from the element frames, integrate
// (eqs. 2-3), then resolve contacts. A vertex reads only its own position here, so the three
// parts fuse into one pass over the vertices, in blocks of kBlock vertices: a block whose
// vertices' steps (start and end positions) lie inside the walls and outside every
// manipulator's swept bounds skips the contact tests. Returns the deepest contact [m].
Real World::stageVertices(size_t begin, size_t end, const ContactBounds* cb) {
  using namespace simd;
  constexpr size_t kBlock = kVertexBlock;
  const size_t surfaces = manipulators_.size() + kWalls;
  const RestModel& m = *model_;
  const Real dt = dt_;
  const Real damp = dampingFactor(uniformDamping_, dt);  // integration.h
  const Real* vertexDamp = vertexDampFactor_.data();     // per vertex when the regions' rates differ
  const d4 g = loadVec3(sim_.gravity);
  Vec3* positions = state_.positions.data();
  Vec3* velocities = state_.velocities.data();
  const Real* invMass = m.invMass.data();
  // Soft-soft contact reads where every vertex started the step (saveBodyContactStart): kept here,
  // from the values this pass loads anyway, instead of a pass of its own.
  Vec3* startX = bodyContacts_ ? bodyContactStartX_.data() : nullptr;
  Vec3* startV = bodyContacts_ ? bodyContactStartV_.data() : nullptr;
  // ... and how far the bodies moved (BodyMotion, per block: stageBodyContacts gathers them).
  BodyMotion* motion = bodyContacts_ ? bodyMotionBlock_.data() : nullptr;
  const RefPoint* reference = bodyContacts_ ? bodyContacts_->referencePositions() : nullptr;
  Real depth = 0;
  // One loop per integrator and per "contacts possible": neither test is made per vertex, and
  // without contacts nothing is kept for them.
  auto run = [&](auto forward, auto contacts, auto perVertexDamping) {
    d4 start[kBlock], startVelocity[kBlock];
    for (size_t b = begin, be; b < end; b = be) {
      be = std::min(end, (b / kBlock + 1) * kBlock);  // blocks aligned to kBlock (the contact forces' partial sums)
      d4 lo = splat(std::numeric_limits<Real>::infinity()), hi = -lo;
      d4 moved2 = splat(0), since2 = splat(0);  // (addMotion, lane per axis, from the values at hand)
      bool touched = false;
      gatherVertexForces(m, *stageRest_, scratch_->frames.data(), positions, b, be, [&](size_t i, d4 force) {
        const d4 a = force * invMass[i] + g;
        const d4 x0 = loadVec3(positions[i]), v0 = loadVec3(velocities[i]);
        if (startX) storeVec3(startX[i], x0), storeVec3(startV[i], v0);
        d4 x = x0, v = v0;
        Real vd = damp;
        if constexpr (perVertexDamping()) vd = vertexDamp[i];
        if constexpr (forward())
          forwardEulerStep(x, v, a, dt, vd);  // integration.h
        else
          symplecticEulerStep(x, v, a, dt, vd);
        storeVec3(positions[i], x), storeVec3(velocities[i], v);
        if (motion) {
          const d4 d = x - x0, e = x - loadFloat4(reference[i].data());
          moved2 = max(d * d, moved2), since2 = max(e * e, since2);  // (a NaN lane keeps the maximum)
        }
        if constexpr (contacts()) {
          start[i - b] = x0, startVelocity[i - b] = v0;
          lo = min(lo, min(x0, x)), hi = max(hi, max(x0, x));
        }
      });
      if constexpr (contacts()) {
        // Broad phase (a NaN position cannot be changed by a contact, so it may be skipped).
        bool touch = !none(lo < cb->wallLo) || !none(hi > cb->wallHi);
        for (size_t k = 0; !touch && k < cb->lo.size(); ++k) touch = none(hi < cb->lo[k]) && none(lo > cb->hi[k]);
        touched = touch;
        if (touch) {
          ContactForce* impulse = &scratch_->blockImpulse[b / kBlock * surfaces];
          std::fill(impulse, impulse + surfaces, ContactForce{});
          scratch_->blockTouched[b / kBlock] = 1;
          Real& work = scratch_->blockWork[b / kBlock];
          work = 0;
          for (size_t i = b; i < be; ++i) {
            Vec3 previous, previousVelocity;
            storeVec3(previous, start[i - b]), storeVec3(previousVelocity, startVelocity[i - b]);
            depth = std::max(depth, resolveVertexContacts(previous, previousVelocity, positions[i], velocities[i],
                                                          m.mass[i], vertexStiffness_[i], impulse, &work));
          }
        }
      }
      if (motion) {
        BodyMotion& bm = motion[b / kBlock];
        if (touched) {  // a wall or manipulator may have moved a vertex: from the positions now (in cache)
          bm = BodyMotion{};
          addMotion(positions, startX, reference, b, be, bm);
        } else {
          bm.moved2 = {moved2[0], moved2[1], moved2[2]}, bm.since2 = {since2[0], since2[1], since2[2]};
        }
      }
    }
  };
  using Yes = std::true_type;
  using No = std::false_type;
  auto runDamped = [&](auto forward, auto contacts) {
    vertexDamp ? run(forward, contacts, Yes{}) : run(forward, contacts, No{});
  };
  if (sim_.integrator == IntegratorKind::ForwardEuler)
    cb ? runDamped(Yes{}, Yes{}) : runDamped(Yes{}, No{});
  else
    cb ? runDamped(No{}, Yes{}) : runDamped(No{}, No{});
  return depth;
}

// Contacts of one vertex, swept from `previous` (independent per vertex); `previousVelocity` is its
// velocity at the start of the step (the bounce uses the speed at which it crossed a surface, not
// the speed gained inside it: contacts.h). The first pass bounces (sec. 3.5). A vertex pinched
// between surfaces (a manipulator and a wall, or two manipulators) is
// resolved again, up to three more passes, inelastically: repeated elastic reflections between
// two surfaces would pump energy into it. The walls go last in every pass, so no vertex ever
// leaves the box. Returns the deepest penetration found [m].
// `impulse` (one entry per manipulator, then the walls) gets the vertex's impulse m dv from each
// surface and its moment (contact forces); `surface`, when given, the last surface that moved it.
Real World::resolveVertexContacts(const Vec3& previous, const Vec3& previousVelocity, Vec3& x, Vec3& v, Real mass,
                                  Real stiffness, ContactForce* impulse, Real* work, int* surface) const {
  const int dim = model_->dim;
  const Vec3 xFree = x;
  const StepStart start{previousVelocity, dt_, sim_.integrator == IntegratorKind::SymplecticEuler};
  const size_t surfaces = manipulators_.size() + (domain_.enabled ? 1 : 0);
  const size_t K = manipulators_.size();
  Real depth = 0;
  // The contacts' work (contact_work.h): J . u per surface, and how far the surfaces that moved
  // the vertex moved themselves.
  Real w = 0, travel = 0;
  for (int pass = 0; pass < 4; ++pass) {
    const bool bounce = pass == 0;
    Real passDepth = 0;
    for (size_t k = 0; k < K; ++k) {
      const Vec3 before = v;
      const Manipulator& mp = manipulators_[k];
      const Real d = resolveManipulator(mp, previous, x, v, dim, bounce, &start).depth;
      if (d > 0 || v != before) {
        addImpulse(impulse[k], mass * (v - before), x, mp.position, dim);
        // A manipulator growing back from a start overlap (overlaps.h) moves its surface outwards too.
        Vec3 u = mp.velocity;
        const Real growth = k < manipulatorGrowth_.size() ? manipulatorGrowth_[k] : 0;
        if (growth > 0 && (x - mp.position).norm() > 0) u += growth * (x - mp.position).normalized();
        w += mass * (v - before).dot(u), travel = std::max(travel, u.norm() * dt_);
      }
      if (d > 0 && surface) *surface = int(k);
      passDepth = std::max(passDepth, d);
    }
    Vec3 wallDv[kWalls] = {Vec3::Zero(), Vec3::Zero(), Vec3::Zero(), Vec3::Zero(), Vec3::Zero(), Vec3::Zero()};
    const ContactResult r = resolveDomain(domain_, previous, x, v, dim, bounce, &start, wallDv);
    const Real d = r.depth;
    for (int wall = 0; wall < kWalls; ++wall)
      if (wallDv[wall] != Vec3::Zero()) {
        addImpulse(impulse[K + size_t(wall)], mass * wallDv[wall], x, Vec3::Zero(), dim);
        w += mass * wallDv[wall].dot(wallVelocity_[size_t(wall)]);
        travel = std::max(travel, wallVelocity_[size_t(wall)].norm() * dt_);
      }
    if (d > 0 && surface) *surface = int(K) + r.wall;
    passDepth = std::max(passDepth, d);
    depth = std::max(depth, passDepth);
    if (passDepth == 0 || surfaces < 2) break;
  }
  if (work && depth > 0) w += displacementWork(stiffness, previous, xFree, x, travel);
  if (work) *work += w;
  return depth;
}

// Contacts of every vertex from scratch_->previousPositions (the implicit step).
void World::stageContacts(size_t begin, size_t end) {
  scratch_->contactSurface.resize(model_->numVertices());
  for (size_t i = begin; i < end; ++i) {
    scratch_->contactSurface[i] = -1;
    scratch_->contactDepth[i] = resolveVertexContacts(scratch_->previousPositions[i], scratch_->previousVelocities[i],
                                                      state_.positions[i], state_.velocities[i], model_->mass[i],
                                                      vertexStiffness_[i], scratch_->impulse.data(), &scratch_->work,
                                                      &scratch_->contactSurface[i]);
  }
}

// Contact forces: every step starts with zero impulses on every surface ...
void World::beginContactImpulses() {
  const size_t surfaces = manipulators_.size() + kWalls;
  scratch_->impulse.assign(surfaces, ContactForce{});
  const size_t blocks = (model_->numVertices() + kVertexBlock - 1) / kVertexBlock;
  if (scratch_->blockImpulse.size() != blocks * surfaces) {
    scratch_->blockImpulse.assign(blocks * surfaces, ContactForce{});
    scratch_->blockTouched.assign(blocks, 0);
    scratch_->blockWork.assign(blocks, 0.0);
  }
  scratch_->work = 0;
}

// ... and ends with the explicit stage's blocks added in block order (the same sums at any
// thread count), the step's forces (the impulse on the body, negated, over dt) and the average.
void World::finishContactImpulses() {
  const size_t K = manipulators_.size(), surfaces = K + kWalls;
  std::vector<ContactForce>& J = scratch_->impulse;
  for (size_t b = 0; b < scratch_->blockTouched.size(); ++b) {
    if (!scratch_->blockTouched[b]) continue;
    scratch_->blockTouched[b] = 0;
    scratch_->work += scratch_->blockWork[b];
    for (size_t s = 0; s < surfaces; ++s)
      J[s].force += scratch_->blockImpulse[b * surfaces + s].force,
          J[s].torque += scratch_->blockImpulse[b * surfaces + s].torque;
  }
  stepForces_.manipulators.resize(K);
  averageImpulse_.manipulators.resize(K);
  // The walls together: their impulses summed in wall order (each the same at any thread count).
  ContactForce allWalls;
  for (size_t w = 0; w < size_t(kWalls); ++w) allWalls.force += J[K + w].force, allWalls.torque += J[K + w].torque;
  for (size_t s = 0; s <= surfaces; ++s) {
    const ContactForce& j = s < surfaces ? J[s] : allWalls;
    ContactForce& f = s < K ? stepForces_.manipulators[s] : s < surfaces ? stepForces_.wall[s - K] : stepForces_.walls;
    ContactForce& a = s < K          ? averageImpulse_.manipulators[s]
                      : s < surfaces ? averageImpulse_.wall[s - K]
                                     : averageImpulse_.walls;
    f.force = -j.force / dt_, f.torque = -j.torque / dt_;
    a.force -= j.force, a.torque -= j.torque;
  }
  averageTime_ += dt_;
  // The steps' positive totals: a step whose contacts took energy out gives none back to the
  // budget (the walls' restitution would otherwise hide what a later step supplies).
  if (std::isfinite(scratch_->work)) contactWork_ += std::max(Real(0), scratch_->work);
}

ContactForces World::averageContactForces() const {
  ContactForces f = averageImpulse_;
  f.manipulators.resize(manipulators_.size());
  const Real s = averageTime_ > 0 ? 1 / averageTime_ : 0;
  for (ContactForce& c : f.manipulators) c.force *= s, c.torque *= s;
  f.walls.force *= s, f.walls.torque *= s;
  for (ContactForce& c : f.wall) c.force *= s, c.torque *= s;
  return f;
}

void World::restartForceAverage() {
  averageImpulse_ = ContactForces{};
  averageImpulse_.manipulators.resize(manipulators_.size());
  averageTime_ = 0;
}

void World::moveManipulators(Real tNext) {
  for (Manipulator& m : manipulators_) {
    if (m.settings.path.keys.empty()) continue;  // posed from outside
    m.position = m.settings.path.position(tNext);
    m.velocity = m.settings.path.velocity(tNext);
  }
}

namespace {
// The contiguous share [begin, end) of the items 0 .. prefix.size() - 1 for worker `t` of
// `threads`, balanced by work: item i costs (prefix[i + 1] - prefix[i]) + itemCost, where
// prefix is a CSR start array (pairs) and itemCost the fixed cost of an item in pairs. Split
// points are multiples of `unit` items. Every item is handled by exactly one worker and no
// result depends on the split.
inline size_t splitPoint(const std::vector<uint32_t>& prefix, uint64_t itemCost, int t, int threads, size_t unit) {
  const size_t n = prefix.size() - 1;
  if (t <= 0) return 0;
  if (t >= threads) return n;
  auto work = [&](size_t i) { return uint64_t(prefix[i]) + itemCost * i; };  // before item i, increasing
  const uint64_t target = work(n) * uint64_t(t) / uint64_t(threads);
  size_t lo = 0, hi = n;  // first i with work(i) >= target
  while (lo < hi) {
    const size_t mid = (lo + hi) / 2;
    (work(mid) < target ? lo = mid + 1 : hi = mid);
  }
  return std::min(n, (lo + unit / 2) / unit * unit);
}
// Each member's first share of the chunks of `chunk` items, as chunk indices (members + 1).
std::vector<size_t> chunkSplit(const std::vector<uint32_t>& prefix, uint64_t itemCost, int members, size_t chunk) {
  std::vector<size_t> split(size_t(members) + 1);
  for (int t = 0; t <= members; ++t)
    split[size_t(t)] = (splitPoint(prefix, itemCost, t, members, chunk) + chunk - 1) / chunk;
  return split;
}
// Measured costs in pairs (instruction counts, callgrind): an element's moments set-up, rotation
// fit and frame cost about as much as 21 of its pairs; a vertex's integration about 4 of its pairs.
constexpr uint64_t kElementCost = 21, kVertexCost = 4;
// Chunks handed out by the team: ~20-40 us of work each (kElementChunk a multiple of the
// rotation fit's lanes, kVertexChunk of stageVertices' blocks).
constexpr size_t kElementChunk = 256, kVertexChunk = 512;
static_assert(kVertexChunk % kVertexBlock == 0, "chunks hold whole blocks (the contact forces' partial sums)");
// Small bodies are not worth waking threads for.
constexpr size_t kMinVerticesPerThread = 1024;

// GRADEL_THREADING=openmp runs the step in an OpenMP region with a static split instead of the
// team, in a build configured with -DGRADEL_OPENMP_COMPARISON=ON (kept to measure the two against
// each other; docs/speed.md, "Threads"). Without it the variable is ignored, with a warning.
bool useOpenMp() {
  static const bool v = [] {
    const char* s = std::getenv("GRADEL_THREADING");
    const bool asked = s && std::string(s) == "openmp";
#ifdef GRADEL_WITH_OPENMP
    return asked;
#else
    if (asked)
      std::fprintf(stderr, "gradel: GRADEL_THREADING=openmp ignored: built without -DGRADEL_OPENMP_COMPARISON=ON\n");
    return false;
#endif
  }();
  return v;
}
}  // namespace

void World::prepareTeam(int members) {
  if (teamMembers_ == members && team_) return;
  team_ = std::make_unique<ThreadTeam>(members);
  governor_ = std::make_unique<ThreadGovernor>();
  elementQueue_ = std::make_unique<ChunkQueue>(), vertexQueue_ = std::make_unique<ChunkQueue>();
  elementSplit_ = chunkSplit(model_->elemStart, kElementCost, members, kElementChunk);
  vertexSplit_ = chunkSplit(stageRest_->vertexStart, kVertexCost, members, kVertexChunk);
  memberContactDepth_.assign(size_t(members), 0.0);
  teamMembers_ = members;
}

void World::step() {
  if (separatingStartOverlaps()) {
    advanceStartOverlapRelease();
  } else {
    wallVelocity_.fill(Vec3::Zero());
    manipulatorGrowth_.clear();
  }
  if (!externalForce_.empty()) {  // external_force.h: the same impulse before every integrator
    const ExternalImpulse e = applyExternalImpulses(externalForce_, model_->mass, pinSet_.vertices, dt_, model_->dim,
                                                    state_.velocities);
    externalImpulse_ += e.impulse;
    externalWork_ += std::max(Real(0), e.work);
    if (largeStep_) largeStep_->resetEnergyBudget();  // the forces did work
  }
  // (The explicit integrators keep the start in their vertex pass, stageVertices.)
  const bool frameStep = sim_.integrator == IntegratorKind::Implicit || sim_.integrator == IntegratorKind::LargeStep;
  if (bodyContactsOn() && frameStep) saveBodyContactStart();
  if (sim_.integrator == IntegratorKind::Implicit)
    stepImplicit(false);
  else if (sim_.integrator == IntegratorKind::LargeStep)
    stepLargeStep();
  else
    stepExplicit();
  if (bodyContactsOn()) stageBodyContacts();
  finishContactImpulses();  // the ledger closes last: the body-contact stage's wall re-pass is in it
}

// Start overlaps (overlaps.h): the walls are moved out to the bodies, the manipulators shrunk
// until no vertex is inside, and the overlapping pairs of bodies listed; every step then takes
// each back by at most kStartSeparationSpeed dt.
void World::releaseStartOverlaps() {
  domain_ = domainSet_ = separatingStartOverlaps() ? domainSet_ : domain_;
  wallsReleasing_ = false;
  separations_.clear();
  for (size_t k = 0; k < manipulatorScale_.size() && k < manipulators_.size(); ++k)
    manipulators_[k].settings.radius = manipulatorSize_[k][0], manipulators_[k].settings.halfLength = manipulatorSize_[k][1];
  domainSet_ = domain_;
  manipulatorScale_.assign(manipulators_.size(), 1.0);
  manipulatorSize_.clear();
  for (const Manipulator& m : manipulators_) manipulatorSize_.push_back({m.settings.radius, m.settings.halfLength});
  startOverlaps_ = findStartOverlaps(*this);
  const std::vector<StartOverlap>& overlaps = startOverlaps_;
  if (overlaps.empty()) return;
  const RestModel& rm = *model_;
  std::vector<uint8_t> pinnedBody(rm.bodies.size(), 0);
  for (uint32_t u : pinSet_.vertices)
    for (size_t b = 0; b < rm.bodies.size(); ++b)
      if (u >= rm.bodies[b].vertexBegin && u < rm.bodies[b].vertexEnd) pinnedBody[b] = 1;
  for (const StartOverlap& o : overlaps) {
    if (o.with == StartOverlap::With::Wall) {
      const int a = int(o.other) / 2;
      if (o.other % 2 == 0)
        domain_.min[a] = std::min(domain_.min[a], domainSet_.min[a] - o.depth);
      else
        domain_.max[a] = std::max(domain_.max[a], domainSet_.max[a] + o.depth);
      wallsReleasing_ = true;
    } else if (o.with == StartOverlap::With::Manipulator) {
      Real& scale = manipulatorScale_[o.other];
      if (scale < 1) continue;  // (found for all bodies' vertices at once)
      Manipulator& m = manipulators_[o.other];
      scale = freeManipulatorScale(m, state_.positions.data(), state_.positions.size(), rm.dim);
      m.settings.radius = scale * manipulatorSize_[o.other][0];
      m.settings.halfLength = scale * manipulatorSize_[o.other][1];
    } else if (!pinnedBody[o.body] || !pinnedBody[o.other]) {
      Separation sep;
      sep.a = uint32_t(o.body), sep.b = uint32_t(o.other), sep.direction = o.direction, sep.remaining = o.depth;
      Real ma = 0, mb = 0;
      for (uint32_t u = rm.bodies[o.body].vertexBegin; u < rm.bodies[o.body].vertexEnd; ++u) ma += rm.mass[u];
      for (uint32_t u = rm.bodies[o.other].vertexBegin; u < rm.bodies[o.other].vertexEnd; ++u) mb += rm.mass[u];
      // The centre of mass stays: a moves mb / (ma + mb) of the way, b the rest; a pinned body stays.
      sep.weightA = pinnedBody[o.body] ? 0 : pinnedBody[o.other] ? 1 : mb / (ma + mb);
      sep.weightB = 1 - sep.weightA;
      separations_.push_back(sep);
    }
  }
}

void World::advanceStartOverlapRelease() {
  const Real step = kStartSeparationSpeed * dt_;
  wallVelocity_.fill(Vec3::Zero());
  if (wallsReleasing_) {
    wallsReleasing_ = false;
    for (int a = 0; a < 3; ++a) {
      const Real lo = std::min(domainSet_.min[a], domain_.min[a] + step);
      const Real hi = std::max(domainSet_.max[a], domain_.max[a] - step);
      wallVelocity_[size_t(2 * a)][a] = (lo - domain_.min[a]) / dt_;
      wallVelocity_[size_t(2 * a + 1)][a] = (hi - domain_.max[a]) / dt_;
      domain_.min[a] = lo, domain_.max[a] = hi;
      wallsReleasing_ = wallsReleasing_ || domain_.min[a] != domainSet_.min[a] || domain_.max[a] != domainSet_.max[a];
    }
  }
  manipulatorGrowth_.assign(manipulators_.size(), 0.0);
  for (size_t k = 0; k < manipulatorScale_.size() && k < manipulators_.size(); ++k) {
    Real& scale = manipulatorScale_[k];
    if (scale >= 1) continue;
    manipulatorGrowth_[k] = kStartSeparationSpeed;
    const auto& size = manipulatorSize_[k];
    const Real reach = manipulators_[k].settings.shape == ManipulatorShape::Cylinder ? std::max(size[0], size[1]) : size[0];
    scale = std::min(Real(1), scale + step / reach);
    manipulators_[k].settings.radius = scale < 1 ? scale * size[0] : size[0];
    manipulators_[k].settings.halfLength = scale < 1 ? scale * size[1] : size[1];
  }
  const RestModel& rm = *model_;
  // Each pair's overlap along its direction is measured again every step (the bodies move
  // meanwhile): they are moved apart by at most kStartSeparationSpeed dt plus the speed at
  // which they close, until the extents no longer overlap.
  for (Separation& sep : separations_) {
    const BodyRange &A = rm.bodies[sep.a], &B = rm.bodies[sep.b];
    Real top = -std::numeric_limits<Real>::infinity(), bottom = std::numeric_limits<Real>::infinity();
    Vec3 va = Vec3::Zero(), vb = Vec3::Zero();
    Real ma = 0, mb = 0;
    for (uint32_t u = A.vertexBegin; u < A.vertexEnd; ++u)
      top = std::max(top, state_.positions[u].dot(sep.direction)), va += rm.mass[u] * state_.velocities[u],
      ma += rm.mass[u];
    for (uint32_t u = B.vertexBegin; u < B.vertexEnd; ++u)
      bottom = std::min(bottom, state_.positions[u].dot(sep.direction)), vb += rm.mass[u] * state_.velocities[u],
      mb += rm.mass[u];
    const Real closing = std::max(Real(0), (va / ma - vb / mb).dot(sep.direction));
    sep.remaining = std::isfinite(top - bottom) ? top - bottom : 0;
    const Real d = std::min(step + closing * dt_, sep.remaining);
    if (d <= 0) continue;
    sep.remaining -= d;
    const Vec3 da = -sep.weightA * d * sep.direction, db = sep.weightB * d * sep.direction;
    for (uint32_t u = A.vertexBegin; u < A.vertexEnd; ++u) state_.positions[u] += da;
    for (uint32_t u = B.vertexBegin; u < B.vertexEnd; ++u) state_.positions[u] += db;
  }
  separations_.erase(std::remove_if(separations_.begin(), separations_.end(),
                                    [](const Separation& s) { return s.remaining <= 0; }),
                     separations_.end());
}

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
  scratch_->maxContactDepth = std::max(scratch_->maxContactDepth, bodyContactStats_.maxDepth);
  if (!domain_.enabled || bodyContacts_->contacts().empty()) return;
  std::vector<uint32_t> moved;
  for (const BodyContacts::Contact& c : bodyContacts_->contacts()) {
    moved.push_back(c.vertex);
    moved.insert(moved.end(), c.face.begin(), c.face.end());
  }
  std::sort(moved.begin(), moved.end());
  moved.erase(std::unique(moved.begin(), moved.end()), moved.end());
  const size_t K = manipulators_.size();
  for (uint32_t u : moved) {
    if (bodyContactInvMass_[u] == 0) continue;
    const StepStart start{bodyContactStartV_[u], dt_, sim_.integrator == IntegratorKind::SymplecticEuler};
    Vec3 wallDv[kWalls] = {Vec3::Zero(), Vec3::Zero(), Vec3::Zero(), Vec3::Zero(), Vec3::Zero(), Vec3::Zero()};
    resolveDomain(domain_, bodyContactStartX_[u], x[u], v[u], model_->dim, false, &start, wallDv);
    // The walls' impulses go into the step's force ledger (closed after this stage, World::step).
    for (int wall = 0; wall < kWalls; ++wall)
      if (wallDv[wall] != Vec3::Zero()) {
        addImpulse(scratch_->impulse[K + size_t(wall)], model_->mass[u] * wallDv[wall], x[u], Vec3::Zero(), model_->dim);
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
    const uint64_t key = uint64_t(c.vertex) << 32 | c.faceBody;
    auto it = std::lower_bound(bodyContactLambda_.begin(), bodyContactLambda_.end(), std::make_pair(key, Real(0)),
                               [](const auto& a, const auto& b) { return a.first < b.first; });
    const Real lambda = it != bodyContactLambda_.end() && it->first == key ? it->second : 0;
    const Real gap = kPairGap * bodyContacts_->bodies()[c.faceBody].thickness;
    pairs.push_back({c.vertex, c.face, c.w, c.n, gap, lambda});
    keys.push_back(key);
  }
  return pairs;
}

void World::keepBodyPairLambdas(const std::vector<PairConstraint>& pairs, const std::vector<uint64_t>& keys) {
  bodyContactLambda_.clear();
  for (size_t j = 0; j < pairs.size(); ++j)
    if (pairs[j].lambda > 0) bodyContactLambda_.push_back({keys[j], pairs[j].lambda});
  std::sort(bodyContactLambda_.begin(), bodyContactLambda_.end());  // proximity lists by vertex within a pair of bodies
}

// The large step's broad phase for the bodies: the boxes of their boundary vertices over the
// step (start and free-flight end), grown by the bodies' voxel size, overlap.
bool World::bodyContactsMayTouch() const {
  if (!bodyContactsOn()) return false;
  std::vector<Vec3> end(state_.positions.size());
  for (const ContactBody& b : bodyContacts_->bodies())
    for (uint32_t u : b.vertices)
      end[u] = state_.positions[u] + dt_ * state_.velocities[u] + 0.5 * dt_ * dt_ * sim_.gravity;
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

// The members a step runs on: the threads asked for, at most one per kMinVerticesPerThread vertices.
int World::stepMembers() const {
  return int(
      std::max<size_t>(1, std::min<size_t>(size_t(sim_.threads), model_->numVertices() / kMinVerticesPerThread)));
}

// The team of a frame-size step's solvers (null: one thread).
ThreadTeam* World::frameStepTeam() {
  const int members = stepMembers();
  if (members == 1) return nullptr;
  prepareTeam(members);
  return team_.get();
}

void World::stepExplicit() {
  const size_t V = model_->numVertices(), E = model_->numElements();
  const int members = stepMembers();
  moveManipulators(state_.time + dt_);  // the elements do not see them; the contacts see t + dt
  const bool contacts = !manipulators_.empty() || domain_.enabled;
  ContactBounds bounds;
  if (contacts) bounds = contactBounds();
  beginContactImpulses();
  const ContactBounds* cb = contacts ? &bounds : nullptr;
  auto runOnThisThread = [&] {
    stageElementFrames(0, E);
    scratch_->maxContactDepth = stageVertices(0, V, cb);
  };
  if (members == 1) {
    runOnThisThread();
  } else if (useOpenMp()) {
#ifdef GRADEL_WITH_OPENMP
    Real depth = 0;
#pragma omp parallel num_threads(members) reduction(max : depth)
    {
      const int t = omp_get_thread_num(), T = omp_get_num_threads();
      stageElementFrames(splitPoint(model_->elemStart, kElementCost, t, T, kRotationLanes),
                         splitPoint(model_->elemStart, kElementCost, t + 1, T, kRotationLanes));
#pragma omp barrier
      depth = stageVertices(splitPoint(stageRest_->vertexStart, kVertexCost, t, T, kVertexBlock),
                            splitPoint(stageRest_->vertexStart, kVertexCost, t + 1, T, kVertexBlock), cb);
    }
    scratch_->maxContactDepth = depth;
#endif
  } else {
    // One job per step: element chunks, a barrier, vertex chunks (thread_team.h), with all
    // members or one, as the governor finds faster on this machine now.
    prepareTeam(members);
    const auto t0 = std::chrono::steady_clock::now();
    if (governor_->choose(members) == 1) {
      runOnThisThread();
    } else {
      elementQueue_->reset(elementSplit_), vertexQueue_->reset(vertexSplit_);
      team_->run([&](int t) {
        size_t c;
        while (elementQueue_->claim(t, &c)) stageElementFrames(c * kElementChunk, std::min(E, (c + 1) * kElementChunk));
        team_->barrier();
        Real depth = 0;
        while (vertexQueue_->claim(t, &c))
          depth = std::max(depth, stageVertices(c * kVertexChunk, std::min(V, (c + 1) * kVertexChunk), cb));
        memberContactDepth_[size_t(t)] = depth;
      });
      scratch_->maxContactDepth = *std::max_element(memberContactDepth_.begin(), memberContactDepth_.end());
    }
    governor_->report(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
  for (Manipulator& m : manipulators_) m.previousPosition = m.position;
  state_.time += dt_;
  if (!pinSet_.empty()) applyPins(state_.time);
  bodyMotionMeasured_ = bodyContacts_ != nullptr;  // (stageVertices)
}

void World::setPins(std::vector<PinSettings> pins) {
  std::vector<std::array<uint32_t, 2>> bodies;
  for (const BodyRange& b : model_->bodies) bodies.push_back({b.vertexBegin, b.vertexEnd});
  pinSet_ = selectPins(pins, model_->restPositions, bodies);
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
  for (size_t k = 0; k < vertices.size(); ++k) externalForce_[vertices[k]] += forces[k];
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
    state_.velocities[i] = pins_[pinSet_.pinOf[j]].path.velocity(t);
    if (model_->dim == 2) state_.positions[i].z() = 0, state_.velocities[i].z() = 0;
  }
}

// The end of an implicit or large step: deepest contact, manipulators' sweep start, time, pins
// (the force ledger closes in World::step, after the body contacts).
void World::finishFrameStep(Real tNext) {
  scratch_->maxContactDepth = scratch_->contactDepth.empty()
                                  ? 0
                                  : *std::max_element(scratch_->contactDepth.begin(), scratch_->contactDepth.end());
  for (Manipulator& m : manipulators_) m.previousPosition = m.position;
  state_.time = tNext;
  if (!pinSet_.empty()) applyPins(state_.time);
}

// Implicit step (projective.h): solve with pinned vertices eliminated, then the same contact
// stage as the explicit path (positions projected, velocity rules applied to the derived
// velocities (x_new - x_old) / dt). `largeStep` (a large step near contacts): fast manipulators
// are swept along their paths.
void World::stepImplicit(bool largeStep) {
  if (!projective_) projective_ = std::make_unique<ProjectiveSolver>(*model_, dt_, pinSet_.vertices);
  projective_->setTeam(frameStepTeam());  // the factor's solves (the same bits at any count, projective.h)
  beginContactImpulses();
  const Vec3 g = sim_.gravity;
  const bool contacts = !manipulators_.empty() || domain_.enabled;
  if (contacts) scratch_->previousPositions = state_.positions, scratch_->previousVelocities = state_.velocities;
  scratch_->contactDepth.assign(model_->numVertices(), 0.0);
  const Real tNext = state_.time + dt_;
  const std::vector<Vec3> x0 = state_.positions, v0 = state_.velocities;
  const std::vector<Quat> q0 = state_.rotations;
  const std::vector<Vec3> targets = pinTargets(tNext);
  projective_->step(state_.positions, state_.velocities, state_.rotations, g, sim_.damping, sim_.implicitIterations,
                    targets, sim_.rotationIterations);
  moveManipulators(tNext);
  if (contacts || bodyContactsOn()) {
    // The contact pass finds the vertices that ended inside a surface; the step is solved again
    // with them held at their projected positions, so that the support reaches the whole body
    // within the step (projecting only those vertices afterwards lets a body sink and crush at
    // frame-size steps). A last pass then applies the contact rules to the final state.
    // The holds are one-sided (projective.h): each carries the direction it pushed its vertex out.
    // Contacts between bodies: every boundary vertex near another body at the end of the first
    // solve is a pair constraint of the second (projective.h); the stage after the step
    // (stageBodyContacts) is the safety net.
    const std::vector<Vec3> freeEnd = state_.positions;
    std::vector<uint32_t> held;
    std::vector<Vec3> heldAt, heldNormal;
    if (contacts) {
      // The vertices a swept manipulator hit are held where the sweep left them, as those the
      // contact pass pushed out (left free, the second solve restarted without them, or without a
      // second solve they kept their flight alone: at dt = 1/30 s the struck ball's E x1000 step
      // ended with 7,770 J of elastic energy, the explicit run's peak 2.8 J).
      std::vector<Real> swept;
      if (largeStep) sweepManipulatorPaths(tNext - dt_), swept = scratch_->contactDepth;
      stageContacts(0, model_->numVertices());
      for (uint32_t i = 0; i < model_->numVertices(); ++i) {
        const Vec3 push = state_.positions[i] - freeEnd[i];
        if ((scratch_->contactDepth[i] > 0 || (!swept.empty() && swept[i] > 0)) && push.norm() > 0)
          held.push_back(i), heldAt.push_back(state_.positions[i]), heldNormal.push_back(push.normalized());
      }
    }
    std::vector<uint64_t> pairKeys;
    std::vector<PairConstraint> pairs;
    // Found at the start of the step, where no vertex is inside another body and each vertex's
    // nearest face is the one it approaches, out to the voxel size plus the two largest distances
    // a body's surface moved in the first solve: every vertex that could reach a face of another
    // body within the step. (Found at the end of the first solve, within the voxel size, a vertex
    // that moved deeper than that into the other body had no constraint: two balls closing at
    // 1 m/s ended steps a voxel inside each other, and at 10 m/s passed through each other.)
    if (bodyContactsOn()) {
      Real first = 0, second = 0;
      for (const ContactBody& b : bodyContacts_->bodies()) {
        Real moved = 0;
        for (uint32_t u : b.vertices) moved = std::max(moved, (freeEnd[u] - x0[u]).norm());
        if (moved > first)
          second = first, first = moved;
        else
          second = std::max(second, moved);
      }
      pairs = bodyPairConstraints(x0, bodyContactMargin() + first + second, pairKeys);
    }
    if (!held.empty() || !pairs.empty()) {
      // Contact forces: the held solve's multipliers (the force holding each vertex, times dt)
      // are the impulse the contacts give the body, each on the surface that moved it; the last
      // contact pass adds its own velocity changes. The first pass's are dropped with its state.
      std::vector<int> heldSurface(held.size());
      for (size_t j = 0; j < held.size(); ++j) heldSurface[j] = scratch_->contactSurface[held[j]];
      scratch_->impulse.assign(manipulators_.size() + kWalls, ContactForce{});
      scratch_->work = 0;
      state_.positions = x0, state_.velocities = v0, state_.rotations = q0;
      std::vector<Vec3> heldForces;
      // Each hold with its surface's friction: a hold on a frictionless surface slides (projective.h).
      std::vector<Real> heldFriction(held.size());
      for (size_t j = 0; j < held.size(); ++j) {
        const size_t k = size_t(std::max(0, heldSurface[j]));
        heldFriction[j] = k < manipulators_.size() ? manipulators_[k].settings.friction : domain_.friction;
      }
      projective_->step(state_.positions, state_.velocities, state_.rotations, g, sim_.damping, sim_.implicitIterations,
                        targets, sim_.rotationIterations, held, heldAt, heldNormal, &heldForces, &pairs, heldFriction);
      for (size_t j = 0; j < held.size(); ++j) {
        // Every held vertex was moved by a surface (a wall: K + its kWalls index).
        const size_t k = size_t(std::max(0, heldSurface[j]));
        const Vec3 centre = k < manipulators_.size() ? manipulators_[k].position : Vec3::Zero();
        addImpulse(scratch_->impulse[k], heldForces[j] * dt_, heldAt[j], centre, model_->dim);
      }
      keepBodyPairLambdas(pairs, pairKeys);
      if (contacts) {
        if (largeStep) sweepManipulatorPaths(tNext - dt_);
        stageContacts(0, model_->numVertices());
      }
    } else {
      bodyContactLambda_.clear();
    }
  }
  finishFrameStep(tNext);
}

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
  const int substeps = sim_.largeStepSubsteps;
  if (!largeStep_)
    largeStep_ =
        std::make_unique<LargeStepSolver>(*model_, dt_ / substeps, pinSet_.vertices, sim_.largeStepCoarseNodes);
  largeStep_->setTeam(frameStepTeam());  // element forces and factor solves (the same bits at any count)
  const Vec3 g = sim_.gravity;           // projected into a 2D body's plane by the constructor
  const bool contacts = !manipulators_.empty() || domain_.enabled;
  const Real tNext = state_.time + dt_;
  beginContactImpulses();
  if (bodyContactsMayTouch()) {  // contacts between bodies: constraints of the implicit step
    stepImplicit(true);
    largeStep_->resetEnergyBudget();
    return;
  }
  bodyContactLambda_.clear();
  if (contacts) {
    const std::vector<Manipulator> before = manipulators_;
    moveManipulators(tNext);
    const int dim = model_->dim;
    auto gap = [&](const Vec3& p) {
      Real best = std::numeric_limits<Real>::infinity();
      for (const Manipulator& mp : manipulators_) {
        Vec3 q = p;
        if (dim == 2) q.z() = mp.position.z();
        best = std::min(best, mp.signedDistance(q, nullptr));
      }
      if (domain_.enabled)
        for (int a = 0; a < dim; ++a) best = std::min({best, p[a] - domain_.min[a], domain_.max[a] - p[a]});
      return best;
    };
    bool near = scratch_->maxContactDepth > 0;
    const Real margin = *std::min_element(model_->size.begin(), model_->size.end());
    for (size_t i = 0; !near && i < model_->numVertices(); ++i) {
      const Vec3& x = state_.positions[i];
      near = gap(x + dt_ * state_.velocities[i] + 0.5 * dt_ * dt_ * g) < margin || gap(x) < margin;
    }
    for (size_t k = 0; !near && k < manipulators_.size(); ++k)
      near = (manipulators_[k].position - before[k].position).norm() > 0.5 * manipulators_[k].settings.radius;
    manipulators_ = before;
    if (near) {
      stepImplicit(true);
      largeStep_->resetEnergyBudget();  // the contacts did work
      return;
    }
    scratch_->previousPositions = state_.positions, scratch_->previousVelocities = state_.velocities;
  }
  scratch_->contactDepth.assign(model_->numVertices(), 0.0);
  for (int k = 0; k < substeps; ++k) {
    const std::vector<Vec3> pinStart = pinTargets(state_.time + dt_ * k / substeps);
    const std::vector<Vec3> pinEnd = pinTargets(k + 1 == substeps ? tNext : state_.time + dt_ * (k + 1) / substeps);
    largeStep_->step(state_.positions, state_.velocities, state_.rotations, g, sim_.damping, sim_.largeStepPasses,
                     sim_.rotationIterations, pinStart, pinEnd);
  }
  moveManipulators(tNext);
  if (contacts) {
    stageContacts(0, model_->numVertices());  // the guarantee: no vertex left inside
    if (std::any_of(scratch_->contactDepth.begin(), scratch_->contactDepth.end(), [](Real d) { return d > 0; }))
      largeStep_->resetEnergyBudget();
  }
  finishFrameStep(tNext);
}

// A manipulator that moves more than its size within the step could cross the body between
// the step's two poses (a strike at 100 m/s moves 1.7 m in 1/60 s): its scripted path is swept
// in sub-intervals of at most its size (up to 256), each vertex moving along its step,
// straight, until a sub-interval's swept contact test (resolveManipulator) hits it; from then on
// it flies with the velocity the contact gave it (the manipulator's velocity at that time,
// reflected by its restitution). A vertex that was hit is marked so that the contact stage
// does not sweep the whole step again for it (its start is moved with the manipulator).
void World::sweepManipulatorPaths(Real t0) {
  const RestModel& m = *model_;
  const size_t V = m.numVertices();
  for (const Manipulator& mp : manipulators_) {
    const Path& path = mp.settings.path;
    if (path.keys.empty()) continue;
    const Real size = mp.settings.shape == ManipulatorShape::Cylinder
                          ? std::min(mp.settings.radius, mp.settings.halfLength)
                          : mp.settings.radius;
    constexpr int kProbe = 16, kMaxSub = 256;
    Real length = 0;
    for (int k = 1; k <= kProbe; ++k)
      length += (path.position(t0 + dt_ * k / kProbe) - path.position(t0 + dt_ * (k - 1) / kProbe)).norm();
    const int K = std::min(kMaxSub, int(std::ceil(length / size)));
    if (K <= 1) continue;
    std::vector<Vec3> centre(size_t(K) + 1), velocity(size_t(K) + 1);
    for (int k = 0; k <= K; ++k) centre[size_t(k)] = path.position(t0 + dt_ * k / K);
    // Each sub-interval's mean velocity: a strike that ends within a sub-interval still hits at its speed.
    for (int k = 1; k <= K; ++k) velocity[size_t(k)] = (centre[size_t(k)] - centre[size_t(k) - 1]) * (K / dt_);
    Manipulator sub;
    sub.settings.shape = mp.settings.shape, sub.settings.radius = mp.settings.radius;
    sub.settings.halfLength = mp.settings.halfLength, sub.settings.axis = mp.settings.axis;
    sub.settings.restitution = mp.settings.restitution, sub.settings.friction = mp.settings.friction;
    const Real h = dt_ / K;
    for (size_t i = 0; i < V; ++i) {
      const Vec3 xs = scratch_->previousPositions[i], xe = state_.positions[i];
      Vec3 x = xs, v = scratch_->previousVelocities[i];
      Real depth = 0;
      for (int k = 1; k <= K; ++k) {
        sub.previousPosition = centre[size_t(k) - 1], sub.position = centre[size_t(k)],
        sub.velocity = velocity[size_t(k)];
        Vec3 xk = depth > 0 ? Vec3(x + h * v) : Vec3(xs + (xe - xs) * (Real(k) / K));
        Vec3 vk = depth > 0 ? v : state_.velocities[i];
        const StepStart start{v, h};
        const Real d = resolveManipulator(sub, x, xk, vk, m.dim, true, &start).depth;
        if (d > 0 || depth > 0) v = vk;
        depth = std::max(depth, d);
        x = xk;
      }
      if (depth == 0) continue;
      // Contact forces: the velocity the sweep gave the vertex, against the one it ended the solve with.
      addImpulse(scratch_->impulse[size_t(&mp - manipulators_.data())], m.mass[i] * (v - state_.velocities[i]), x,
                 mp.position, m.dim);
      scratch_->work += m.mass[i] * (v - state_.velocities[i]).dot((mp.position - mp.previousPosition) / dt_);
      state_.positions[i] = x, state_.velocities[i] = v;
      scratch_->previousPositions[i] = x - (mp.position - mp.previousPosition);
      scratch_->contactDepth[i] = std::max(scratch_->contactDepth[i], depth);
    }
  }
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

std::vector<Real> World::vertexStress() const { return vertexStress(elementStress()); }

std::vector<Real> World::vertexStress(const std::vector<Real>& elementStress) const {
  const RestModel& m = *model_;
  // Mean over each vertex's elements, summed in element order (deterministic).
  std::vector<Real> sum(m.numVertices(), 0.0);
  std::vector<uint32_t> count(m.numVertices(), 0);
  for (size_t e = 0; e < m.numElements(); ++e)
    for (uint32_t p = m.elemStart[e]; p < m.elemStart[e + 1]; ++p)
      sum[m.elemVerts[p]] += elementStress[e], ++count[m.elemVerts[p]];
  for (size_t i = 0; i < sum.size(); ++i) sum[i] = count[i] ? sum[i] / count[i] : 0;
  return sum;
}

Metrics World::metrics(std::vector<Real>* elementStress) const {
  Metrics r = combineMetrics(bodyMetrics(elementStress));
  r.contactForces = averageContactForces();  // the world's: what all bodies exert together
  return r;
}

Metrics combineMetrics(const std::vector<Metrics>& each) {
  if (each.empty()) throw std::invalid_argument("combineMetrics: no bodies");
  Metrics r = each[0];
  for (size_t k = 1; k < each.size(); ++k) {
    const Metrics& b = each[k];
    r.kineticEnergy += b.kineticEnergy, r.elasticEnergy += b.elasticEnergy, r.gravityEnergy += b.gravityEnergy;
    r.shadowEnergy += b.shadowEnergy;
    r.linearMomentum += b.linearMomentum, r.angularMomentum += b.angularMomentum;
    r.maxStress = std::max(r.maxStress, b.maxStress), r.maxPenetration = std::max(r.maxPenetration, b.maxPenetration);
    r.minElementDet = std::min(r.minElementDet, b.minElementDet);
  }
  return r;
}

std::vector<Metrics> World::bodyMetrics(std::vector<Real>* elementStress) const {
  if (elementStress) elementStress->assign(model_->numElements(), 0.0);
  std::vector<Metrics> r;
  for (const BodyRange& b : model_->bodies) r.push_back(metricsOf(b, elementStress));
  return r;
}

Metrics World::metricsOf(const BodyRange& body, std::vector<Real>* elementStress) const {
  const RestModel& m = *model_;
  Metrics r;
  r.time = state_.time;
  const Vec3 g = sim_.gravity;
  const size_t v0 = body.vertexBegin;

  // Elastic forces and energy at the current positions (the body's elements touch only its vertices).
  std::vector<Vec3> forces(body.numVertices(), Vec3::Zero());
  std::vector<Vec3> f;
  r.minElementDet = std::numeric_limits<Real>::infinity();
  for (size_t e = body.elementBegin; e < body.elementEnd; ++e) {
    const uint32_t b = m.elemStart[e], n = m.elemStart[e + 1] - b;
    f.resize(n);
    Quat q = state_.rotations[e];
    const ElementResult er = elementForces(m.dim, state_.positions.data(), &m.elemVerts[b], &m.restOffsets[b], int(n),
                                           m.stiffness[e], q, f.data(), 20);
    for (uint32_t i = 0; i < n; ++i) forces[m.elemVerts[b + i] - v0] += f[i];
    r.elasticEnergy += er.energy;
    const Real stress = std::sqrt(er.sumSqDisp / n) / m.size[e];
    if (elementStress) (*elementStress)[e] = stress;
    r.maxStress = std::max(r.maxStress, stress);
    r.minElementDet = std::min(r.minElementDet, elementDeterminant(m.dim, state_.positions.data(), &m.elemVerts[b],
                                                                   &m.restOffsets[b], int(n)));
  }

  // Symplectic Euler's stored velocity belongs half a step before its positions (it is the
  // leapfrog v_{n-1/2}); the kinetic energy at time t uses v + a(x) dt / 2, as Stormer-Verlet
  // does. This is what makes the measured energy of an undamped run flat to O(dt^2) rather
  // than swing by O(omega dt). Forward Euler's velocity is already synchronous.
  // The modified energy's term -dt^2/8 m |a|^2 (Metrics::shadowEnergy) makes the total the
  // quantity symplectic Euler keeps: 1/2 m v_{n-1/2} . v_{n+1/2} = 1/2 m |v_n|^2 - dt^2/8 m |a|^2.
  const bool staggered = sim_.integrator == IntegratorKind::SymplecticEuler;
  for (size_t i = body.vertexBegin; i < body.vertexEnd; ++i) {
    const Vec3& x = state_.positions[i];
    Vec3 v = state_.velocities[i];
    if (staggered) {
      const Vec3 a = forces[i - v0] * m.invMass[i] + g;
      v += 0.5 * dt_ * a;
      r.shadowEnergy -= 0.125 * dt_ * dt_ * m.mass[i] * a.squaredNorm();
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
  }
  r.maxContactDepth = scratch_->maxContactDepth;
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

size_t World::memoryBytes() const {
  auto bytes = [](const auto& v) { return v.capacity() * sizeof(v[0]); };
  size_t b = sizeof(*this) + model_->memoryBytes() + stageRest_->memoryBytes();
  b += bytes(state_.positions) + bytes(state_.velocities) + bytes(state_.rotations);
  b += bytes(scratch_->frames) + bytes(scratch_->previousPositions) + bytes(scratch_->previousVelocities) +
       bytes(scratch_->contactDepth) + bytes(scratch_->impulse) + bytes(scratch_->blockImpulse) +
       bytes(scratch_->blockTouched) + bytes(scratch_->contactSurface);
  b += (elementSplit_.capacity() + vertexSplit_.capacity()) * sizeof(size_t);
  for (const Manipulator& m : manipulators_) b += sizeof(m) + bytes(m.settings.path.keys);
  b += bytes(bodyContactStartX_) + bytes(bodyContactStartV_) + bytes(bodyContactInvMass_);
  if (bodyContacts_)
    for (const ContactBody& c : bodyContacts_->bodies())
      b += bytes(c.vertices) + bytes(c.triangles) + bytes(c.vertexTriStart) + bytes(c.vertexTris) + bytes(c.nearStart) +
           bytes(c.near);
  return b;
}

}  // namespace gradel
