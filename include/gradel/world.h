// A simulated world of one or more bodies (bodies.h: one combined rest model): rest model
// (shared, immutable) + runtime state + manipulators + walls, advanced by a list of named stages
// (Box2D style; src/step_context.h): begin (the step's constants, the force ledger opened) ->
// integrator advance (explicit: element frames, eq. 1, then per vertex the elastic force,
// eqs. 2-3, and the obstacle contacts, element_stage.h; implicit; or large step), pins -> body
// contacts -> the walls' re-pass -> finish (the ledger closed last). Every stage runs over an
// index range; threads only split ranges and never change the order in which any sum is formed
// (a vertex sums its elements in id order), so results are identical at any thread count.
#pragma once

#include <algorithm>
#include <array>
#include <memory>
#include <string>
#include <vector>

#include "gradel/body_contacts.h"
#include "gradel/contacts.h"
#include "gradel/external_force.h"
#include "gradel/integrator.h"
#include "gradel/large_step.h"
#include "gradel/model.h"
#include "gradel/overlaps.h"
#include "gradel/pins.h"
#include "gradel/projective.h"
#include "gradel/stability.h"
#include "gradel/world_settings.h"

namespace gradel {

class ThreadTeam;
class ContactEnergyLimiter;
class ChunkQueue;
class ThreadGovernor;
struct ElementStageRest;
struct StepContext;

/// Runtime state: what changes every step.
struct State {
  Real time = 0;                 ///< [s]
  std::vector<Vec3> positions;   ///< [m] per vertex.
  std::vector<Vec3> velocities;  ///< [m/s] per vertex.
  std::vector<Quat> rotations;   ///< Best-fit rotation per element (warm start of eq. 1).
};

/// The force [N] and torque [N m] the body exerts on one contact surface: minus the momentum the
/// contact response gave the body's vertices (their velocity changes m dv, summed), over the time.
struct ContactForce {
  Vec3 force{0, 0, 0};   ///< [N]
  Vec3 torque{0, 0, 0};  ///< [N m] about the manipulator's centre (walls: about the world origin).
};

/// The contact forces on every surface: one per manipulator (in index order), each wall of the
/// domain box (contacts.h kWalls: xmin, xmax, ymin, ymax, zmin, zmax; torques about the world
/// origin) and the walls together. Newton's third law holds: the manipulators' and the walls'
/// sum is minus the momentum the contacts gave the body.
struct ContactForces {
  std::vector<ContactForce> manipulators;
  std::array<ContactForce, kWalls> wall;  ///< Per wall, by kWalls index.
  ContactForce walls;                     ///< All walls: the sum of `wall` in index order.
};

/// Material carving took from one body since t = 0 (carve_scene.h; World::recordRemoval).
struct RemovedMaterial {
  size_t voxels = 0;       ///< Voxels removed.
  Real volume = 0;         ///< [m^3] voxels x h^3 (a 2D body's voxel is a slab one voxel thick).
  Real mass = 0;           ///< [kg] the removed voxels' mass (rho h^3 each, their region's rho).
  Vec3 momentum{0, 0, 0};  ///< [kg m/s] the removed material's momentum when it left (carve.h).
};

/// Figures written per frame to metrics.csv.
struct Metrics {
  Real time = 0;                  ///< [s]
  Real kineticEnergy = 0;         ///< [J]
  Real elasticEnergy = 0;         ///< [J]
  Real gravityEnergy = 0;         ///< [J] -sum m g.x (relative to the origin)
  /// [J] symplectic Euler's modified-energy term -dt^2/8 sum m |a|^2 (a: the vertex's elastic plus
  /// gravity acceleration at the current positions; 0 for the other integrators). With it,
  /// totalEnergy() = sum 1/2 m v_{n-1/2} . v_{n+1/2} + elastic + gravity, which symplectic Euler
  /// keeps exactly on linear forces; the kinetic energy alone (synchronised velocity) swings by up
  /// to a factor 1 / (1 - (omega dt / 2)^2) in a mode of frequency omega. Not positive-definite
  /// above the stability limit (omega dt > 2), so the divergence guard uses kinetic + elastic.
  Real shadowEnergy = 0;
  /// [J] kinetic + elastic + gravity + shadowEnergy: flat on an undamped, contact-free run.
  Real totalEnergy() const { return kineticEnergy + elasticEnergy + gravityEnergy + shadowEnergy; }
  Vec3 linearMomentum{0, 0, 0};   ///< [kg m/s]
  Vec3 angularMomentum{0, 0, 0};  ///< [kg m^2/s] about the world origin.
  Real maxStress = 0;             ///< [Pa] max per-element von Mises stress (World::elementStress, nu = 0).
  Real maxStrain = 0;             ///< [-] max per-element strain measure (World::elementStrain).
  Real maxPenetration = 0;        ///< [m] deepest vertex inside a manipulator or outside the walls now (should be 0).
  Real maxContactDepth = 0;       ///< [m] deepest vertex found (and corrected) in the last step.
  Real minElementDet = 0;         ///< [-] min det of the elements' deformation estimate (< 0: inverted).
  ContactForces contactForces;    ///< Averaged since the last restartForceAverage() (the frame, in `gradel run`).
  RemovedMaterial removed;        ///< Carved away since t = 0 (World::removedMaterial); summed over bodies.
};

/// The figures of several bodies together: energies, momenta and removed material summed in order, the largest
/// stress, strain and penetration, the smallest determinant; time and maxContactDepth the first's.
Metrics combineMetrics(const std::vector<Metrics>& bodies);

class World {
 public:
  /// The complete world in one call (world_settings.h): dt and its rule, the manipulators, the
  /// pins (their vertices moved to their targets), contact between the bodies over
  /// `contactBodies` (buildContactBodies; empty: none), the start overlaps' release and the
  /// bodies' initial velocities, in that order. InputError for settings out of range, a pin that
  /// holds no vertex or body contact in 2D; std::invalid_argument for a bodyVelocities entry
  /// count other than the model's bodies. A 2D world keeps its bodies in the plane z = 0: every
  /// input is put into it where it enters (gravity, initial velocities here; manipulator paths and
  /// poses, pin paths, external forces and a replaced state by the methods below), so no step
  /// stage projects anything (src/plane.h). Writing state() directly is the caller's business.
  World(std::shared_ptr<const RestModel> model, WorldSettings settings, std::vector<ContactBody> contactBodies = {});
  /// A bare world (tests, tools): no pins, no body contacts, at rest, start overlaps pushed out
  /// by the contacts at once unless its owner calls releaseStartOverlaps().
  World(std::shared_ptr<const RestModel> model, const SimulationSettings& sim, const DomainSettings& domain,
        std::vector<ManipulatorSettings> manipulators);
  ~World();
  World(World&&) noexcept;
  World& operator=(World&&) noexcept;

  /// Advances one time step dt().
  void step();
  /// Finds the overlaps of the bodies with each other, the manipulators and the walls now
  /// (overlaps.h) and separates them at kStartSeparationSpeed from the next step on, instead of
  /// the contacts' instant push. World(model, WorldSettings) calls it (at t = 0, after the pins
  /// and the contacts between bodies are set, WorldSettings::releaseStartOverlaps); a bare world
  /// keeps the instant push unless its owner calls it.
  void releaseStartOverlaps();
  /// What the last releaseStartOverlaps() found (the warnings of `gradel run`).
  const std::vector<StartOverlap>& startOverlaps() const { return startOverlaps_; }
  /// True while start overlaps are being separated (walls or manipulators on their way back to
  /// their settings, bodies moving apart; contacts between bodies wait for the bodies).
  bool separatingStartOverlaps() const {
    return wallsReleasing_ || !separations_.empty() ||
           std::any_of(manipulatorScale_.begin(), manipulatorScale_.end(), [](Real s) { return s < 1; });
  }
  /// Advances by whole steps until time() >= t (within half a step).
  void advanceTo(Real t);

  Real time() const { return state_.time; }
  Real dt() const { return dt_; }
  const RestModel& model() const { return *model_; }
  std::shared_ptr<const RestModel> modelPtr() const { return model_; }
  const State& state() const { return state_; }
  State& state() { return state_; }  ///< For tests and tools: set positions / velocities directly.
  /// The settings as applied (a 2D body's gravity projected into its plane; with integrator
  /// "auto" on input, `integrator` is the one chosen).
  const SimulationSettings& settings() const { return sim_; }
  /// Which integrator "auto" chose and why (empty when the integrator was given).
  const std::string& integratorChoice() const { return integratorChoice_; }
  /// Where dt came from, in words: "given", "one frame (1/60 s)", or the rule and its numbers,
  /// e.g. "operator x 0.2: 2 pi / omega_max, omega_max 4.1e+04 rad/s" (shown by `gradel run`'s
  /// JSON summary and the viewer).
  const std::string& dtRule() const { return dtRule_; }
  /// The body's fastest vibration at rest (stability.h), measured when dt_period is "operator"
  /// (all zero otherwise): dt = dt_fraction 2 pi / omega.
  const FrequencyEstimate& stabilityEstimate() const { return frequency_; }
  const DomainSettings& domain() const { return domain_; }

  std::vector<Manipulator>& manipulators() { return manipulators_; }
  const std::vector<Manipulator>& manipulators() const { return manipulators_; }
  /// Adds a manipulator at its path's pose now, or at `position` [m] without a path (then posed
  /// from outside with setManipulatorPose). Normalises a cylinder's axis; InputError for a
  /// non-positive radius or a zero axis. Returns its index. 2D: the path and pose in the plane.
  size_t addManipulator(ManipulatorSettings settings, const Vec3& position = Vec3::Zero());
  /// Sets a manipulator's pose from outside (viewer, script); used for manipulators without a path.
  /// 2D: position and velocity put into the plane (z = 0).
  void setManipulatorPose(size_t i, const Vec3& position, const Vec3& velocity);

  /// Contact forces (contacts.h): what the body exerts on each manipulator and on the walls.
  /// The last step's: the impulse its contact response gave the body, negated, over dt.
  const ContactForces& stepContactForces() const { return stepForces_; }
  /// Averaged over the steps since the last restartForceAverage() (impulse over that time; zero
  /// when no step was made): what a frame of output or a haptic device wants.
  ContactForces averageContactForces() const;
  /// The time [s] the average covers.
  Real forceAverageTime() const { return averageTime_; }
  /// The energy [J] the walls and manipulators gave the bodies since t = 0 (contact_work.h): the
  /// sum of each step's positive total; what the divergence guard counts as supplied by contacts.
  Real contactWork() const { return contactWork_; }
  void restartForceAverage();

  /// Soft-soft contact between the bodies and, if set, of a body with itself (body_contacts.h):
  /// their contact surfaces (buildContactBodies), made once; replaces any before (the World's
  /// creation sets them from its contact surfaces). It runs after each step, serially.
  /// InputError for a 2D model.
  void setBodyContacts(std::vector<ContactBody> bodies, const BodyContactSettings& settings);
  /// The stage (nullptr without body contacts) and what it found in the last step.
  const BodyContacts* bodyContacts() const { return bodyContacts_.get(); }
  BodyContacts* bodyContacts() { return bodyContacts_.get(); }  ///< For tests and tools (its switches).
  const BodyContactStats& bodyContactStats() const { return bodyContactStats_; }

  /// External forces [N] on vertices (external_force.h): added to those set before, they act in
  /// every step until clearExternalForces(), as the impulse F dt at the start of each step in
  /// every integrator. InputError for a vertex id out of range, a non-finite force or sizes that
  /// differ. 2D: the forces' z is dropped here.
  void addExternalForces(const std::vector<uint32_t>& vertices, const std::vector<Vec3>& forces);
  void clearExternalForces() { externalForce_.clear(); }
  /// Per vertex, the external force acting now (empty: none).
  const std::vector<Vec3>& externalForces() const { return externalForce_; }
  /// The energy [J] the external forces gave the bodies since t = 0 (the sum of each step's
  /// positive total): what the divergence guard counts as supplied by them.
  Real externalWork() const { return externalWork_; }
  /// The impulse [N s] the external forces gave the bodies since t = 0: their momentum is
  /// conserved up to it (and to gravity, walls, manipulators and pins).
  const Vec3& externalImpulse() const { return externalImpulse_; }

  void setThreads(int n) { sim_.threads = n < 1 ? 1 : n; }

  /// Carving (carve_scene.h): the world over a new model, e.g. with one body laid out again, and
  /// its state (`state`: one entry per vertex and element of `model`, the time kept). Keeps the
  /// settings as applied, dt (dt = auto of symplectic Euler under the operator rule: estimated
  /// again on the new model; under the other rules shortened by the ratio of the models' smallest
  /// vertex periods when the new one's is shorter, never lengthened; a given dt as it is), the
  /// manipulators (poses), walls, pins (moved to their targets),
  /// the force averages and the work and impulse ledgers; body contacts over `contactBodies`
  /// with the same settings (empty: none). External forces and the frame-size integrators'
  /// warm starts (vertex ids) are dropped; derived rest data, scratch and threads are made anew
  /// (src/world_replace.cpp). std::invalid_argument when the state's sizes are not the model's.
  /// 2D: the state's positions and velocities put into the plane.
  /// `pins` (optional): the pins of the new world (bodies that fell apart, carve_scene.h); null:
  /// the pins as they are. Contact surfaces given to a world that had no body contacts switch
  /// them on with the settings it was made with (WorldSettings::bodyContact). The removed-material
  /// ledger grows to the new model's bodies (zeros for new ones).
  /// `fromVertex` (optional): per vertex of the new model, its vertex id in the current one
  /// (UINT32_MAX for a new vertex). With it the operator rule's estimate is warm started from the
  /// previous one's Ritz vector (stability_warm.h: kWarmStartIterations products instead of 48)
  /// once this world holds one (made with a carving manipulator, or replaced before); otherwise
  /// the estimate is made from scratch and its Ritz vector kept.
  void replaceModel(std::shared_ptr<const RestModel> model, State state, std::vector<ContactBody> contactBodies,
                    const std::vector<PinSettings>* pins = nullptr, const std::vector<uint32_t>* fromVertex = nullptr);
  /// Carving's ledger (carve_scene.h): adds what an event took from body `body` (RestModel::bodies
  /// index) to its total since t = 0, kept across replaceModel. The linear momentum of body b now
  /// plus removedMaterial()[b].momentum is what it would have been without carving.
  void recordRemoval(size_t body, const RemovedMaterial& removed);
  /// Per body, what carving took from it since t = 0 (empty before the first event); also in
  /// metrics() and bodyMetrics() (Metrics::removed).
  const std::vector<RemovedMaterial>& removedMaterial() const { return removed_; }

  /// Boundary conditions (pins.h): replaces the pins (WorldSettings::pins at creation) and moves
  /// the pinned vertices to their prescribed positions now (a pin added while running: Python's
  /// add_pin). Throws InputError when a pin holds no vertex. 2D: the paths' offsets in the plane.
  void setPins(std::vector<PinSettings> pins);
  const std::vector<PinSettings>& pins() const { return pins_; }
  const PinSet& pinned() const { return pinSet_; }

  /// Per-element von Mises stress [Pa] (element_strain.h): from the element's small strain about
  /// its best-fit rotation and its region's Young's modulus and Poisson's ratio (material.h).
  /// Per-vertex: mean over its elements.
  std::vector<Real> elementStress() const;
  std::vector<Real> vertexStress() const;
  /// Per-element strain measure (sec. 3, fig. 1) [-]: RMS over its vertices of |M R0_i - r_i|,
  /// divided by the element size. Per-vertex: mean over the vertex's elements.
  std::vector<Real> elementStrain() const;
  std::vector<Real> vertexStrain() const;
  /// Per vertex, the mean over its elements of a per-element field (elementStress(),
  /// elementStrain()) already at hand.
  std::vector<Real> vertexStress(const std::vector<Real>& perElement) const;

  Metrics metrics() const { return metrics(nullptr); }
  /// The same, and, when elementStress / elementStrain are given, elementStress() and
  /// elementStrain() from the same pass over the elements (what a written frame needs: one
  /// reference-kernel pass per frame, not two).
  Metrics metrics(std::vector<Real>* elementStress, std::vector<Real>* elementStrain = nullptr) const;
  /// The same figures per body (RestModel::bodies, bodies.h), over its vertices and elements;
  /// metrics() is their sum (energies, momenta) and extremes. maxContactDepth is the world's;
  /// contactForces is left empty (forces are the world's: metrics()). elementStress as metrics().
  std::vector<Metrics> bodyMetrics(std::vector<Real>* elementStress = nullptr,
                                   std::vector<Real>* elementStrain = nullptr) const;
  /// FNV-1a hash of the positions and velocities (bitwise): equal states give equal hashes.
  uint64_t stateHash() const;
  /// Bytes held by the world: rest model, state, scratch and manipulators (capacities).
  size_t memoryBytes() const;

 private:
  /// The bare world with the operator rule's estimate given (replaceModel) instead of made here.
  World(std::shared_ptr<const RestModel> model, const SimulationSettings& sim, const DomainSettings& domain,
        std::vector<ManipulatorSettings> manipulators, const FrequencyEstimate* frequency);
  struct ContactBounds;
  struct HeldContacts;
  void beginStep();
  void advanceIntegrator();
  void stageElementFrames(size_t begin, size_t end);
  Real stageVertices(size_t begin, size_t end, const ContactBounds* contacts, int member);
  ContactBounds contactBounds() const;
  Metrics metricsOf(const BodyRange& body, std::vector<Real>* elementStress, std::vector<Real>* elementStrain) const;
  void prepareTeam(int members);
  int stepMembers() const;
  ThreadTeam* frameStepTeam();
  /// The team an estimate of omega_max runs on (stability.h): the step's own when this thread made
  /// it, else one made in `local` for the estimate (a world may be made on one thread and stepped
  /// on another: the step's team must be made by the stepping thread); null for one thread.
  ThreadTeam* estimateTeam(std::unique_ptr<ThreadTeam>& local) const;
  void stageContacts(size_t begin, size_t end);
  Real resolveVertexContacts(const Vec3& previous, const Vec3& previousVelocity, Vec3& x, Vec3& v, Real mass,
                             Real stiffness, ContactForce* impulse, Real* work, int* surface = nullptr) const;
  void beginContactImpulses();
  void finishContactImpulses();
  void moveManipulators(Real tNext);
  void stepExplicit();
  void saveBodyContactStart();
  void stageBodyContacts();
  void updateBodyContactInvMass();
  Real bodyContactMargin() const;
  std::vector<PairConstraint> bodyPairConstraints(const std::vector<Vec3>& x, Real margin, std::vector<uint64_t>& keys);
  void keepBodyPairLambdas(const std::vector<PairConstraint>& pairs, const std::vector<uint64_t>& keys);
  void clearBodyPairLambdas();
  bool bodyContactsMayTouch() const;
  void stepImplicit(bool largeStep);
  HeldContacts heldObstacleContacts(const std::vector<Vec3>& freeEnd, bool largeStep);
  void touchingAtStart(HeldContacts& held) const;
  std::vector<PairConstraint> stepBodyPairs(const std::vector<Vec3>& x0, const std::vector<Vec3>& freeEnd,
                                            std::vector<uint64_t>& keys);
  void solveHeld(const State& start, const std::vector<Vec3>& targets, const HeldContacts& held,
                 std::vector<PairConstraint>& pairs);
  void stepLargeStep();
  bool largeStepNearObstacles() const;
  void finishFrameStep(Real tNext);
  void sweepManipulatorPaths(Real t0);
  void chooseIntegrator(Real period);
  void advanceStartOverlapRelease();
  bool bodyContactsOn() const { return bodyContacts_ && separations_.empty(); }
  void applyPins(Real t);
  std::vector<Vec3> pinTargets(Real t) const;

  std::shared_ptr<const RestModel> model_;
  std::unique_ptr<const ElementStageRest> stageRest_;  ///< Derived rest data of the explicit stages (element_stage.h).
  SimulationSettings sim_;
  DomainSettings domain_;
  std::vector<Manipulator> manipulators_;
  State state_;
  std::unique_ptr<StepContext> scratch_;  ///< The step's context: constants, start state, ledger (step_context.h).
  Real dt_ = 0;
  // Velocity damping of the explicit step (integration.h): one rate for every vertex (today's
  // path), or per vertex when regions set different rates (model.h RestModel::vertexDamping).
  Real uniformDamping_ = 0;             ///< [1/s] the rate of every vertex when vertexDampFactor_ is empty.
  std::vector<Real> vertexDampFactor_;  ///< Per vertex: 1 / (1 + c_i dt); empty: all share uniformDamping_.
  std::string integratorChoice_;
  std::string dtRule_;
  FrequencyEstimate frequency_;  ///< World(): the operator rule's estimate (stability.h).
  /// The Ritz vector of the last operator-rule estimate (per vertex), the next replaceModel's warm
  /// start (stability_warm.h): kept by World() when a manipulator carves (or is a blade) and by
  /// every replaceModel with a vertex map; empty otherwise.
  std::vector<Vec3> ritz_;
  std::vector<PinSettings> pins_;
  PinSet pinSet_;
  std::unique_ptr<ProjectiveSolver>
      projective_;  ///< Implicit, and LargeStep near contacts: built at the first such step.
  std::unique_ptr<LargeStepSolver> largeStep_;  ///< LargeStep only: built at the first step (dt, pins fixed).
  // Threads of the explicit step (thread_team.h): the team, its chunk queues and each member's
  // first share of the element and vertex chunks, made for `teamMembers_`. The vertex shares are
  // weighted by work; the element chunks ([begin, end) each, elementChunks_) are grouped by the
  // member whose vertex share holds their elements' first vertex (prepareTeam).
  std::unique_ptr<ThreadTeam> team_;
  std::unique_ptr<ThreadGovernor> governor_;  ///< All members or one, whichever is faster now.
  std::unique_ptr<ChunkQueue> elementQueue_, vertexQueue_;
  std::vector<size_t> elementSplit_, vertexSplit_;
  std::vector<std::pair<uint32_t, uint32_t>> elementChunks_;
  std::vector<Real> memberContactDepth_;
  // Soft-soft contact: the stage, its last result, the boundary vertices' start of the step
  // (full-size arrays, only the bodies' boundary vertices written) and the inverse masses it uses.
  std::unique_ptr<BodyContacts> bodyContacts_;
  std::unique_ptr<ContactEnergyLimiter> contactEnergy_;  ///< The stage's energy cap (body_contact_energy.h), made on first use.
  BodyContactSettings bodyContactSettings_;  ///< WorldSettings::bodyContact (replaceModel: contacts switched on).
  BodyContactStats bodyContactStats_;
  std::vector<Vec3> bodyContactStartX_, bodyContactStartV_;
  std::vector<Real> bodyContactInvMass_;
  // How far the bodies moved in an explicit step (BodyMotion), measured in its vertex pass per
  // block of vertices: per block the body whose vertices it holds (or kMixedBlock: measured after
  // the pins), the blocks' and the bodies' motion.
  static constexpr uint32_t kMixedBlock = 0xffffffffu;
  std::vector<uint32_t> bodyMotionBlockBody_;
  std::vector<BodyMotion> bodyMotionBlock_, bodyMotion_;
  bool bodyMotionMeasured_ = false;  ///< The last step's vertex pass filled bodyMotionBlock_.
  int teamMembers_ = 0;
  ContactForces stepForces_;      ///< The last step's contact forces.
  ContactForces averageImpulse_;  ///< [N s], [N m s] summed since restartForceAverage().
  Real averageTime_ = 0;          ///< [s] since restartForceAverage().
  std::vector<Real> vertexStiffness_;  ///< [N/m] per vertex: sum of its elements' k_e (contact_work.h).
  Real contactWork_ = 0;               ///< [J] World::contactWork().
  std::vector<Vec3> externalForce_;    ///< [N] per vertex (empty: none); addExternalForces().
  Real externalWork_ = 0;              ///< [J] World::externalWork().
  Vec3 externalImpulse_{0, 0, 0};      ///< [N s] World::externalImpulse().
  std::vector<RemovedMaterial> removed_;  ///< Per body: World::removedMaterial().
  // Start overlaps (overlaps.h), released from the first step on at kStartSeparationSpeed.
  DomainSettings domainSet_;             ///< The walls as set (domain_: where they are while released).
  bool wallsReleasing_ = false;
  std::vector<Real> manipulatorScale_;   ///< Per manipulator: its size now over its set size (1: set).
  std::vector<std::array<Real, 2>> manipulatorSize_;  ///< Per manipulator: set radius and half length.
  struct Separation {
    uint32_t a = 0, b = 0;        ///< Bodies (RestModel::bodies).
    Vec3 direction{1, 0, 0};      ///< b moves along it, a against it.
    Real remaining = 0;           ///< [m] still to go.
    Real weightA = 0.5, weightB = 0.5;  ///< Shares of each move (mass-weighted; 0 for a pinned body).
  };
  std::vector<Separation> separations_;
  std::vector<StartOverlap> startOverlaps_;
  std::array<Vec3, kWalls> wallVelocity_{};  ///< [m/s] per wall, this step (moving only while released).
  std::vector<Real> manipulatorGrowth_;     ///< [m/s] per manipulator: its surface's growth speed this step.
};

}  // namespace gradel
