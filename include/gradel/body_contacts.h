// Soft-soft contact (issue 12): a surface vertex of one body never ends a step inside another
// body, and (behind a setting) a body folding onto itself does not pass through itself.
// How the stage works and what it measured, phase by phase: docs/speed.md, "Body contacts: the stage".
//
// The stage runs after the positions of a step are known; resolve() is its loop of rounds over
// named phases, each in a file of its own:
//   contact surface  contact_surface.h: each body's closed voxel surface in world vertex ids
//   broad phase      body_contact_tracks.cpp: per ordered pair of bodies, the candidate vertices
//                    and the faces they may reach, kept across steps in a grid
//                    (body_contact_grid.cpp); body_contact_bounds.cpp: how far the surfaces moved
//                    (body_motion.h) and which candidates may have reached a face since their check
//   narrow phase     body_contact_narrow_phase.cpp: the nearest triangle (triangle_queries.h) and
//                    the angle-weighted pseudo-normal sign test (src/pseudo_normal.h)
//   response         body_contact_response.cpp: projections split by inverse mass, friction,
//                    restitution; impulses that never add kinetic energy
//   warm start       body_contact_warm_start.cpp: the last stage's contacts as round 0's
//   last resort      body_contact_takeback.cpp: findings no step can reach dropped; bodies still
//                    deep in each other taken back towards the step's start
//   frame-size steps body_contact_proximity.cpp: the contacts as constraints of the solve
// Everything runs in a fixed order (pairs of bodies in index order, vertices in id order, ties
// between triangles broken by id); the result does not depend on the thread count.
// 3D only: a 2D body's display surface is a flat region, not a closed surface.
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <memory>
#include <utility>
#include <vector>

#include "gradel/body_contact_stats.h"
#include "gradel/body_motion.h"
#include "gradel/contact_surface.h"
#include "gradel/model.h"
#include "gradel/surface.h"
#include "gradel/triangle_queries.h"
#include "gradel/types.h"

namespace gradel {

class ThreadTeam;

/// Scene key "body_contact" (docs/scenes.md).
struct BodyContactSettings {
  Real restitution = 0.5;    ///< [-] of body-body contacts (as the walls' default); 0 = no bounce.
  Real friction = 0.0;       ///< [-] Coulomb coefficient between bodies.
  bool selfContact = false;  ///< Also a body against its own non-adjacent faces.
};

/// Checks the settings; InputError naming "body_contact.<key>".
void validate(const BodyContactSettings& s);

/// The combined state the stage reads and corrects (world vertex ids; all arrays of one length).
struct BodyContactState {
  Vec3* positions = nullptr;                 ///< [m] end of the step: corrected in place.
  Vec3* velocities = nullptr;                ///< [m/s] end of the step: corrected in place.
  const Vec3* previousPositions = nullptr;   ///< [m] start of the step (every vertex of a body: the last resort).
  const Vec3* previousVelocities = nullptr;  ///< [m/s] start of the step (the bounce).
  const Real* invMass = nullptr;             ///< [1/kg] 0 = immovable (pinned).
  /// Per body (bodies() order), measured by the caller at these positions, or nullptr: the stage measures it.
  const BodyMotion* motion = nullptr;
  Real dt = 0;            ///< [s] the step (0: unknown; the response then stores no projection energy).
  bool leapfrog = false;  ///< Velocities half a step behind the positions (symplectic Euler; contacts.h StepStart).
};

/// The stage: contact surfaces of the bodies and the per-step scratch.
class BodyContacts {
 public:
  BodyContacts();
  BodyContacts(std::vector<ContactBody> bodies, const BodyContactSettings& settings);
  BodyContacts(BodyContacts&&) noexcept;
  BodyContacts& operator=(BodyContacts&&) noexcept;
  ~BodyContacts();

  /// Resolves every body-body (and, if on, self) contact of the step, in place. With a team
  /// (setTeam), the narrow phase of the pairs runs on its members, each vertex's finding into its
  /// own slot, gathered in pair then vertex order: the same result at any thread count.
  BodyContactStats resolve(const BodyContactState& state);
  /// The world's thread team for the narrow phase (nullptr: serial), used for a round with at least
  /// `minParallel` vertices to look up (below it, waking the team costs more than the work). Not owned.
  void setTeam(ThreadTeam* team, uint32_t minParallel = kMinParallel) { team_ = team, minParallel_ = minParallel; }
  static constexpr uint32_t kMinParallel = 128;
  /// Whether the stage keeps its tracks across steps and rounds (the default). Off: every round
  /// rebuilds them and looks up every candidate from scratch, the reference that keeping them
  /// must match bit for bit (tests; it costs a full detection per round).
  void setKeepTracks(bool keep) { keepTracks_ = keep; }
  /// Whether each stage starts from the contacts the last one ended with (the default; header,
  /// "warm start"). Off: every contact is found by the detection rounds (the reference, tests).
  void setWarmStart(bool warm) { warmStart_ = warm, cache_.contacts.clear(), cache_.at.clear(); }
  /// Whether the stage uses the motion a caller measured (BodyContactState::motion; the default)
  /// or measures it in its own pass (measure()), the reference the caller's must match (tests).
  void setUseGivenMotion(bool use) { useGivenMotion_ = use; }

  const std::vector<ContactBody>& bodies() const { return bodies_; }
  /// Per world vertex: its position at the tracks' last rebuild (BodyMotion).
  const RefPoint* referencePositions() const { return ref_.data(); }
  const BodyContactSettings& settings() const { return settings_; }
  bool empty() const { return bodies_.size() < 2 && !settings_.selfContact; }

  static constexpr int kRounds = 8;          ///< Detection rounds per step at most.
  static constexpr int kIterations = 4;      ///< Gauss-Seidel sweeps over the contacts per round, at least.
  static constexpr int kMaxIterations = 32;  ///< ... and at most (while a sweep finds one inside along its normal).
  /// The last resort halves the taken-back bodies' motion down to this fraction, then takes it all back.
  static constexpr Real kTakeBackLeast = 1.0 / 16;
  /// ... while a vertex is inside deeper than this (times the voxel size of the face's body).
  static constexpr Real kTakeBackDepth = 0.1;

  struct Contact {
    uint32_t vertex;               ///< World id of the vertex.
    std::array<uint32_t, 3> face;  ///< World ids of the touched face's corners.
    std::array<Real, 3> w;         ///< Barycentric weights of the contact point on the face.
    Vec3 n;                        ///< Unit normal, out of the face's body.
    Real depth;                    ///< [m] how far inside, before correction.
  };
  /// The contacts the last resolve() found (all rounds, in order).
  const std::vector<Contact>& contacts() const { return contacts_; }
  /// The vertices the last resolve() may have moved (its contacts' vertices and face corners), and
  /// where each was and how fast it moved when the stage began.
  const std::vector<uint32_t>& touched() const { return touched_; }
  const std::vector<Vec3>& touchedStart() const { return touchedStart_; }
  const std::vector<Vec3>& touchedStartVelocity() const { return touchedStartV_; }

  /// What one step's body contacts leave for the next, in one place (Jolt and Bullet keep one
  /// contact cache): the explicit stage's warm start and the frame-size steps' multipliers.
  /// The two are keyed differently on purpose: a contact of the explicit stage is its (vertex,
  /// face), since a vertex carried against two faces of a body must stay out of both (one per
  /// vertex: 724 lookups a step against 545, docs/speed.md "Body contacts: the stage"); a
  /// multiplier is its (vertex, face's body), since the frame-size solve's constraint is the
  /// vertex's nearest face of that body, which changes from step to step while the push goes on.
  struct Cache {
    /// The last explicit stage's body-body contacts, one per (vertex, face), in that stage's order,
    /// and where each one's vertex and face corners ended it (4 per contact: keepWarm).
    std::vector<Contact> contacts;
    std::vector<Vec3> at;
    /// The last frame-size step's pair multipliers [N] by (vertex << 32 | face's body), sorted.
    std::vector<std::pair<uint64_t, Real>> multipliers;

    /// The multiplier the last frame-size step left on `vertex` against body `faceBody` (0: none).
    Real multiplier(uint32_t vertex, uint32_t faceBody) const;
    /// Keeps the positive multipliers of this step's pairs (keys[j]: pair j's (vertex, body) key).
    void keepMultipliers(const std::vector<uint64_t>& keys, const std::vector<Real>& lambdas);
    static uint64_t key(uint32_t vertex, uint32_t faceBody) { return uint64_t(vertex) << 32 | faceBody; }
  };
  Cache& cache() { return cache_; }
  const Cache& cache() const { return cache_; }

  // ---- For the frame-size integrators (implicit, large_step): the contacts as constraints of
  // their solve (projective.h, PairConstraint), this stage after the step as the safety net.

  /// A surface vertex near a face of another body: the nearest triangle of that body within
  /// `margin`, whether the vertex is in front of it or behind (the pseudo-normal sign test).
  struct Proximity {
    uint32_t vertex;               ///< World id of the vertex.
    uint32_t faceBody;             ///< Index of the face's body (bodies()).
    std::array<uint32_t, 3> face;  ///< World ids of the nearest face's corners.
    std::array<Real, 3> w;         ///< Barycentric weights of the nearest point on it.
    Vec3 n;                        ///< Unit normal out of the face's body at that point.
    Real gap;                      ///< [m] n . (vertex - point): < 0 inside.
  };
  /// Every body-body Proximity at positions x (pairs of bodies in index order, vertices in id
  /// order, ties to the lowest triangle id: the same list at any thread count). The pairs of
  /// bodies whose boxes, grown by `margin`, overlap; self-contact is not included.
  void proximity(const Vec3* x, Real margin, std::vector<Proximity>& out);
  /// Broad phase of a step: whether two bodies' boxes over the step (the box of each boundary
  /// vertex's start x and predicted end xEnd), grown by `margin`, overlap.
  bool mayTouch(const Vec3* x, const Vec3* xEnd, Real margin) const;

 private:
  struct Box {  ///< Axis-aligned; default: empty (grows with add).
    Vec3 lo = Vec3::Constant(std::numeric_limits<Real>::infinity());
    Vec3 hi = Vec3::Constant(-std::numeric_limits<Real>::infinity());
    void add(const Vec3& p) { lo = lo.cwiseMin(p), hi = hi.cwiseMax(p); }
    void add(const Box& b) { lo = lo.cwiseMin(b.lo), hi = hi.cwiseMax(b.hi); }
  };
  // A face grid of one body and a pair of bodies' track across steps: the broad phase's own
  // types (src/body_contact_tracks.h).
  struct Grid;
  struct Track;
  void rebuildTracks(const Vec3* x);
  void buildTrack(size_t a, size_t b, const Vec3* x);
  void measure(const BodyContactState& s);
  void setMotion(size_t b, const BodyMotion& m);
  bool tracksHold() const;
  Real searchRadius(size_t a, size_t b) const;
  // A pair's part of a detection pass (preparePair, detectPairs): its lookups are
  // looked_[begin, end); a == b: self-contact (detectSelf, when gathered).
  struct PairJob {
    uint32_t a, b;
    Real r;              ///< [m] search radius.
    bool smallStep;      ///< detectVertex.
    Real faceMoved;      ///< [m] sinceRebuild_[b] now.
    Real faceCorrected;  ///< [m] corrected_[b] now.
    uint32_t begin, end;
  };
  void preparePair(size_t a, size_t b, const BodyContactState& s);
  void detectPairs(const BodyContactState& s, BodyContactStats& stats, const std::vector<uint8_t>& pick);
  void detectSelf(size_t a, const BodyContactState& s, BodyContactStats& stats);
  bool detectAll(const BodyContactState& s, BodyContactStats& stats);
  void dropUnreachable(const BodyContactState& s, BodyContactStats& stats);
  void takeBack(const BodyContactState& s, BodyContactStats& stats);
  // resolve()'s phases besides those above: the broad phase's bounds of a round and the pairs it
  // detects (body_contact_bounds.cpp), the response (body_contact_response.cpp).
  void measureRound(const BodyContactState& s, int round);
  void pickPairs(bool onlyMoved);
  void returnToStart(const BodyContactState& s);
  void projectPositions(const BodyContactState& s);
  void applyImpulses(const BodyContactState& s);
  void addContacts(const BodyContactState& s);
  Real allowedDepth(const Contact& c, const BodyContactState& s) const;
  void buildGrid(Grid& g, const ContactBody& faces, const Box& region, const Vec3* x,
                 const std::vector<uint32_t>* subset, Real reach, Real grow);
  // Per member of the team: the faces a query listed and the dedupe stamps.
  struct QueryScratch {
    std::vector<uint32_t> candidates;  ///< Indices into the grid's tri.
    std::vector<uint32_t> seen;        ///< Per listed face: the query that last listed it.
    uint32_t stamp = 0;
  };
  void prepareScratch(const Grid& g);
  template <class F>
  void forCandidateTriangles(const Grid& g, const Vec3& lo, const Vec3& hi, QueryScratch& q, F&& f) const;
  // One vertex of a pair's narrow phase (detectPairs): 1 looked up, 2 in contact (into *out);
  // *clearance: a lower bound of its distance to b's surface (< 0: inside, or unknown); hint[0]
  // and hint[1]: its nearest face and its nearest facing face when last found (searches start there).
  int detectVertex(const ContactBody& A, const ContactBody& B, const Grid& g, uint32_t i, Real r, bool smallStep,
                   const Vec3* x, Contact* out, Real* clearance, uint32_t* hint, uint32_t* tests) const;
  struct Nearest {
    Real d2;       ///< [m^2] squared distance to it (reach^2 when none).
    uint32_t tri;  ///< Its id, or kNone.
    ClosestPoint cp;
    uint32_t tests = 0;  ///< Nearest-point tests it made (BodyContactStats::faceTests).
  };
  template <class Accept>
  Nearest nearestTriangle(const Grid& g, const ContactBody& faces, const Vec3& p, Real reach, const Vec3* x,
                          uint32_t hint, Accept&& accept) const;
  Nearest nearestTriangle(const Grid& g, const ContactBody& faces, const Vec3& p, Real reach, const Vec3* x,
                          uint32_t hint = ContactBody::kNone) const;
  void updatePatches(const Vec3* x);
  void markTouched(const Contact& c, const Vec3* x, const Vec3* v);

  std::vector<ContactBody> bodies_;
  BodyContactSettings settings_;
  Real skin_ = 0;   ///< [m] a corrected vertex ends this far outside.
  Real loose_ = 0;  ///< [m] how far a surface may move from the rebuild before the tracks are rebuilt.
  Real rCap_ = 0;   ///< [m] the largest search radius the tracks hold (set at the rebuild).
  // scratch
  std::vector<Box> bounds_;       ///< Per body: its surface's box at the last rebuild.
  std::vector<Real> moved_;       ///< Per body: at least the largest distance a surface vertex moved in the step [m].
  std::vector<Real> movedStart_;  ///< moved_ at round 0 (a later round adds the contacts' vertices).
  std::vector<Real>
      sinceRebuild_;  ///< Per body: at least the farthest a surface vertex is from where it was at the rebuild [m].
  std::vector<Real> sinceRebuildStart_;  ///< sinceRebuild_ at round 0 (a later round adds the contacts' vertices).
  std::vector<RefPoint> ref_;            ///< Per world vertex: its position at the rebuild (rounded).
  std::vector<Vec3> refRounding_;        ///< Per body and axis: the largest |rounding| in its ref_ [m].
  std::vector<Real> sinceAxis_;          ///< Per body: sinceRebuild_ along the farthest axis (tracksHold) [m].
  std::vector<Real> sinceAxisStart_;     ///< sinceAxis_ at round 0.
  std::vector<uint32_t> chunkStart_;     ///< measure(): body b's chunks of vertices from chunkStart_[b].
  std::vector<BodyMotion> chunkMotion_;  ///< measure(): per chunk.
  bool tracksValid_ = false;
  bool keepTracks_ = true;
  bool useGivenMotion_ = true;
  // The boxes per block of kBoundsBlock surface vertices at the rebuild (body b's blocks from
  // blockStart_[b]): a track visits only the blocks near the other body.
  static constexpr uint32_t kBoundsBlock = 256;
  std::vector<uint32_t> blockStart_;
  std::vector<Box> blockBox_;
  std::vector<uint32_t> touched_;    ///< World ids of the vertices of the step's contacts (first-seen order).
  std::vector<uint8_t> isTouched_;   ///< Per world vertex.
  std::vector<Vec3> touchedStart_;   ///< Their positions when the stage began.
  std::vector<Vec3> touchedLast_;    ///< Their positions at the last round's detection.
  std::vector<Vec3> touchedStartV_;  ///< Their velocities when the stage began.
  std::vector<Real> roundShift_;     ///< Per world vertex: how far it moved since the last round's detection [m].
  std::vector<Real> roundShiftMax_;  ///< Per body: the largest roundShift_ of its vertices [m].
  int round_index_ = 0;              ///< The round being detected (resolve).
  // A pair's bound on how far b's faces near a point moved since the last round's detection (round
  // 2 on; preparePair): per cell of its track's grid, the largest shift of a face that moved then
  // and may reach a point of the cell; a point outside the grid's box: outsideShift_.
  std::vector<Real> cellShift_;
  std::vector<uint32_t> shiftSeen_;  ///< shiftCells(): per face of the body, the call that last marked it.
  uint32_t shiftStamp_ = 0;
  std::vector<uint32_t> cellShiftSet_;
  Real outsideShift_ = 0;
  bool shiftCells(size_t a, size_t b, const Vec3* x, Real margin);
  std::vector<Real> corrected_;   ///< Per body: the farthest the stage's corrections moved a vertex of its surface [m].
  uint32_t stage_ = 0;            ///< resolve() calls so far.
  std::vector<uint32_t> bodyOf_;  ///< Per world vertex: the body whose surface holds it (bodies().size(): none).
  std::vector<Track> tracks_;     ///< Per ordered pair (a * bodies + b).
  // Per body: its triangles in patches of kPatch near each other, so that a rebuild visits only
  // the faces of the patches whose box meets a pair's region (updatePatches).
  static constexpr size_t kPatch = 32;
  struct Patches {
    std::vector<uint32_t> tris;              ///< Triangle ids, patch k at [k kPatch, (k + 1) kPatch).
    std::vector<uint32_t> vertStart, verts;  ///< Per patch its distinct corners (CSR).
    std::vector<Box> box;                    ///< Per patch: the box of its corners at the rebuild.
  };
  std::vector<Patches> patches_;
  std::vector<Contact> contacts_, round_;
  /// Per contacts_ entry: the depth [m] its vertex may keep this step (addContacts).
  std::vector<Real> keep_;
  /// Per world vertex: the stage (stage_) in which it was last asked whether it lay inside the
  /// other body of a contact at the step's start, and the answer (allowedDepth).
  mutable std::vector<uint32_t> startAskedStage_, startAskedBody_;
  mutable std::vector<uint8_t> startInside_;
  mutable size_t startWindings_ = 0;  ///< Winding numbers allowedDepth evaluated this stage (stats).
  std::vector<Vec3> entry_;  ///< Per contact: its relative velocity when the velocity response began.
  // The warm start (header): cache_.contacts, used only where the step started where they ended
  // (previousPositions).
  bool warmStart_ = true;
  Cache cache_;
  std::vector<std::pair<std::array<uint32_t, 4>, uint32_t>> warmKeys_;  ///< Scratch of keepWarm: (vertex, face), index.
  bool applyWarm(const BodyContactState& s, BodyContactStats& stats);
  void keepWarm(const Vec3* x);
  std::unique_ptr<Grid> grid_;         ///< For one pass (self-contact, proximity).
  std::vector<QueryScratch> scratch_;  ///< Per member (one when serial).
  ThreadTeam* team_ = nullptr;
  uint32_t minParallel_ = kMinParallel;
  std::vector<Contact> slot_;        ///< Per entry of looked_: its contact, if any.
  std::vector<uint8_t> slotState_;   ///< Per vertex: detectVertex's answer (0: skipped).
  std::vector<uint32_t> slotTests_;  ///< Per vertex: detectVertex's nearest-point tests.
  std::vector<uint32_t> looked_;     ///< The pass's candidates to look up (indices into their pair's track).
  std::vector<uint32_t> lookedJob_;  ///< Per entry of looked_: its pair (index into jobs_).
  std::vector<PairJob> jobs_;        ///< The pass's pairs, in order.
  std::vector<std::array<uint32_t, 2>> boxChunks_;  ///< The pass's chunks of faces' boxes now: (job, first face).
  std::vector<uint8_t> pick_;                       ///< Per (vertex body, face body): detected in this pass.
  std::vector<uint8_t> active_;                     ///< Per (vertex body, face body): contacts in the last round.
  std::vector<uint8_t> movedBodies_;                ///< Per body: a correction of the last round moved its vertices.
};

}  // namespace gradel
