// Soft-soft contact (issue 12): a surface vertex of one body never ends a step inside another
// body, and (behind a setting) a body folding onto itself does not pass through itself.
//
// Each body brings a contact surface: the closed, crack-free voxel display surface of surface.h
// (buildDisplaySurface(..., SurfaceKind::Voxel)), whose corners are model vertices, with its ids
// shifted to the world's vertex numbering (several bodies are one combined state; a body owns the
// vertices [vertexBegin, vertexEnd)). The stage runs after the positions of a step are known:
//
//   broad phase  kept across steps, per ordered pair of bodies (a's vertices against b's
//                faces), a track: b's faces that can come within rCap of a's surface before
//                the next rebuild, in a grid (a dense table of cells of about a voxel, each with
//                its faces' boxes grown by loose = half a voxel: the most a face may move before
//                the rebuild), and a's candidate vertices, those within loose + rCap of such a
//                box (any other one stays farther than rCap from every face of b until then). Per
//                step, how far each body moved in the step and since the rebuild (BodyMotion: per
//                axis the largest squared coordinate difference; the explicit step measures it in
//                its own vertex pass, where the positions are at hand, against the rebuild's
//                positions rounded to float: half the bytes; other steps in a pass of the stage);
//                every track is rebuilt when a surface moved more than loose along an axis since
//                the rebuild (a face then still lies in its box grown by loose) or a pair's search
//                radius r passed rCap (set to the r of the rebuild plus a quarter voxel). A
//                candidate is looked up only when it may have reached b's surface since its last
//                check: it was at least its clearance (the distance to its nearest face, in front)
//                from it then; since, it moved what it moved and b's faces at most what b's
//                surface moved since the rebuild (or, checked in this stage, what the stage's
//                corrections moved it) plus as much then. From round 2 on, a candidate checked in
//                the last round is looked up again only where a face that the last round's
//                corrections moved may have reached it (shiftCells: those faces mark the cells of
//                the pair's grid they can reach). For a closed surface that does not pass through
//                itself the skipped vertices are outside (the same bits as looking them all up:
//                tests KeptTracksGiveTheBitsOfDetectingFromScratch and
//                PressedBallsKeptTracksGiveTheBitsOfDetectingFromScratch; where a crushed body's
//                surface folds through itself the sign test below is no consistent inside/outside
//                and the two can differ). The rounds after the first measure only the vertices
//                the corrections moved (the only ones that moved): the rounds cost the contact
//                area. Each round is one pass over the pairs: their lookups one batch (on the
//                thread team for many), gathered in pair then vertex order.
//   narrow phase the nearest triangle of the other body within r = thickness + the largest
//                distances both bodies' surfaces moved in the step (from the vertex's last answer,
//                which bounds the search; the nearest cell first; a cell or a triangle whose box
//                (now) lies farther than the best so far is skipped; of equally near ones the
//                lowest id wins, whatever the cells' order); inside when the vertex lies
//                behind the nearest feature's angle-weighted pseudo-normal (the face normal in a
//                face, the sum of its faces' normals on an edge, the angle-weighted sum at a
//                corner: Baerentzen & Aanaes 2005), the sign test that is exact for a closed
//                surface that does not pass through itself (a ball folded through itself in a
//                fast off-centre collision at a frame step can leave a vertex that its winding
//                number counts inside in front of its nearest face: docs/scenes.md). A vertex
//                that started the step outside (every step ends with none inside) cannot end it
//                deeper than r, so its nearest triangle is always among the ones looked at: no
//                deep case is missed, whatever the step (a frame step too). Found is not undone:
//                see the last resort below. The converse fails where a soft body is crushed and
//                its surface folds (elements at 40 % of their volume): there the test read
//                vertices that had moved 0.02 voxel as a voxel inside. In an explicit step a
//                finding deeper than the step's motion can reach is asked of the winding number
//                of the other surface and dropped when that says outside (dropUnreachable; two
//                64^3 balls pressed together: none, the same state bits).
//   response     the vertex and the point of the touched face (barycentric weights w) are pushed
//                apart along the normal until the vertex is `skin` outside: the correction is
//                split by inverse mass (generalised inverse mass W = 1/m_p + sum w_k^2 / m_k),
//                the face's share spread over its corners by w_k / m_k, so the sum of m dx is
//                zero. Then equal and opposite impulses on the relative velocity at the contact:
//                the approaching normal part leaves at restitution times the speed at which it
//                approached at the start of the step (a contact that was resting or receding then
//                does not bounce: no energy pumped into resting stacks, as contacts.h), and
//                Coulomb friction removes up to friction times the normal impulse from the
//                sliding. The impulses never add kinetic energy (issue 26, contacts.h's rules):
//                with symplectic Euler they act on the relative velocity at the time of the
//                positions, w = v + a dt / 2 (BodyContactState::leapfrog), a contact with wn >= 0
//                gets none, and each takes wn to at most restitution x |wn| and only shrinks the
//                tangential part, a change of (|w'|^2 - |w|^2) / 2W <= 0 in kinetic energy
//                whatever the impulses before it did on shared vertices; the elastic energy the
//                push stored (depth x the relative acceleration that pressed the vertex in, per
//                unit of generalised mass) comes out of the bounce, then the sliding; friction also undoes the tangential slip of the step up to friction x
//                depth (as the manipulators, contacts.cpp frictionSlipCorrection). Linear momentum
//                is conserved to rounding (every impulse J on the vertex has -w_k J on the face's
//                corners, sum w_k = 1).
//                In a small step (the two surfaces moved at most a quarter voxel together), a
//                vertex in front of some faces around its nearest edge or corner and behind
//                others (a concave feature) is pushed out of the face it is deepest behind, not
//                along c - p, which would carry it round the feature to behind the others.
//                The projections run Gauss-Seidel over the contacts (kIterations sweeps, more up
//                to kMaxIterations while one still finds a vertex behind its contact point along
//                the contact's normal), then the detection runs again (a corrected face can move
//                under a neighbour), up to kRounds rounds; a
//                vertex still inside then (contradicting contacts where two coarse staircases
//                cross, each vertex behind a face of the other) goes back to where it was
//                relative to its face at the start of the step.
//   warm start   a pressed contact is found again every step (the step moves the vertex back
//                behind the face it was pushed out of), and every vertex a round corrects must
//                be looked up again in the next: two lookups or more per contact and step. So a
//                stage begins with the contacts the last one ended with (setWarmStart; on by
//                default): each whose vertex and face corners start this step where that stage
//                left them, in a small step of its pair, and whose vertex lies behind its plane as
//                found (normal n through its point at weights w on the face now; one per vertex
//                and face, the plane as first found while the vertex stays behind it), is round 0's,
//                pushed out like a found one (Gauss-Seidel, friction, then the impulses below);
//                the detection rounds follow and check every candidate as ever (the bounds count
//                what round 0 moved), so the guarantee is unchanged: they find a vertex round 0
//                left inside, or pushed into another face. Two 64^3 balls pressed, 400 steps:
//                575 lookups a step against 971 (docs/speed.md). The result depends on the last
//                stage's contacts, not only on the state: the same scene gives the same bits (at
//                any thread count); a contact whose vertex or face corners were set from outside
//                since is not carried over.
//   last resort  that is not always enough: where the bodies ended deep in each other (more than
//                about a voxel; a frame step whose solve left them so) the nearest-face pushes
//                contradict each other and the rounds move vertices further in, not out (two
//                balls at 1 m/s each way, dt = 1/60 s: depths grew to 10 cm over the 8 rounds,
//                and 6 of 18 steps ended with vertices inside). So after that fallback the
//                detection runs once more from scratch, and while it finds a vertex inside, the
//                bodies of its contacts (growing with each try) go back along the straight line
//                from where they ended to where they started, all by one fraction of the step's
//                motion: 1/2, 1/4, ..., kTakeBackLeast, then 0. At 0 they are where they were at the
//                start of the step, so the stage ends with no vertex inside deeper than
//                kTakeBackDepth of a voxel beyond where it was then (pinned vertices stay at
//                their targets). At kTakeBackLeast the tries stop when every deep vertex was
//                already about as deep (within kTakeBackDepth) behind the same face point, along
//                the same normal, at the step's start: taking the step back cannot undo that
//                (where elements inverted, the sign test read a vertex outside at the start and
//                0.44 voxel inside after 1/16 of the step, which moved it 0.014 voxel), and taking
//                the pair back to that start in every step froze it (two 16^3 balls at 10 m/s,
//                generic build: 2,234 of 2,424 steps taken back, never parted; issue 26). What is
//                left is pushed out once more and kept as contacts. Velocities go back by the same fraction (linear momentum kept: the
//                step's internal forces sum to zero) and get the impulses below: keeping them
//                while the positions went back let a pressed pair's elastic forces accelerate it
//                every step without moving it (two balls at 4 m/s: energy x1e5, issue 26).
//                Where the nearest face does not face the vertex (its normal along the vertex's
//                own), the vertex is pushed out of the nearest face that does, if one is about as
//                near: the risers of interlocking staircases otherwise push both ways at once.
//   self-contact (off by default) a surface vertex against the faces of its own body that share
//                no element with it and are not in its ring of surface faces: it is in contact
//                when it crossed the face's plane within the step (in front at the start, behind
//                at the end, by less than r) and ends over the face. (The pseudo-normal test
//                needs the nearest face, which for a vertex on its own surface is adjacent.)
//
// Everything runs in a fixed order (pairs of bodies in index order, vertices in id order, ties
// between triangles broken by id); a round's narrow phase (every pair's lookups) may run on a
// thread team (setTeam), each vertex into its own slot, gathered in pair then vertex order: the
// result does not depend on the thread count.
// 3D only: a 2D body's display surface is a flat region, not a closed surface.
// Frame-size steps (implicit, large_step): the step's solve carries the contacts itself, as
// one-sided constraints of its PCG (projective.h PairConstraint; World::stepImplicit): proximity()
// lists, at the start of the step, each boundary vertex's nearest face of every other body within
// the voxel size plus the two largest distances a body's surface moved in the step's first,
// contact-free solve (every face a vertex can reach within the step, seen from where nothing is
// inside: a list made at the end of the first solve missed the vertices that had gone deeper than
// its margin, and let balls closing at 10 m/s pass through each other). resolve() then runs after
// the step as the safety net. Measured (two-balls.json, dt = 1/60 s, implicit and large_step): at
// 0.5, 1, 2 and 5 m/s each way the solve leaves vertices at most 1.5, 3.8, 6.5 and 12 mm inside and
// the rounds clear it (no step needs the last resort); at 10 m/s (33 cm a step) one step does.
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

#include "gradel/model.h"
#include "gradel/surface.h"
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

/// One body's contact surface (rest data: built once, read-only). Vertex ids are the world's.
struct ContactBody {
  uint32_t vertexBegin = 0, vertexEnd = 0;  ///< The body's vertices [begin, end).
  Real thickness = 0;                       ///< [m] about the body's voxel size: grid cell and search band.
  /// Its boundary vertices (world ids, ascending): the surface's corners and the model's other
  /// onSurface vertices (inside a merged polygon of a coarse element's face).
  std::vector<uint32_t> vertices;
  std::vector<std::array<uint32_t, 3>> triangles;  ///< World vertex ids, CCW from outside (closed surface).
  // Per boundary vertex (index into `vertices`): its triangles (CSR), for the pseudo-normals (a
  // vertex inside a polygon: the triangles that hold it at rest).
  std::vector<uint32_t> vertexTriStart, vertexTris;
  // Self-contact only: per surface vertex, the world ids of the vertices near it (of its elements
  // and its ring of surface faces), ascending (CSR); a face with a corner among them is adjacent.
  std::vector<uint32_t> nearStart, near;
  /// Per vertex of the body (world id - vertexBegin): its index in `vertices`, or kNone.
  std::vector<uint32_t> indexOf;

  /// Index of a world vertex id in `vertices`, or kNone.
  uint32_t surfaceIndex(uint32_t vertex) const {
    return vertex >= vertexBegin && vertex < vertexEnd ? indexOf[vertex - vertexBegin] : kNone;
  }
  static constexpr uint32_t kNone = 0xffffffffu;
};

/// The elements of a body, compressed rows: element e's vertices are verts[start[e]] .. verts[start[e+1] - 1],
/// for e in [begin, end); a vertex's world id is verts[p] + shift (shift = 0 when `verts` holds world ids
/// already, as in a combined model, or the body's vertex offset for a model of its own).
struct ElementRows {
  const uint32_t* start = nullptr;
  const uint32_t* verts = nullptr;
  size_t begin = 0, end = 0;
  uint32_t shift = 0;
};

/// Builds a body's contact surface from its voxel display surface (model vertex ids of the body,
/// shifted by vertexBegin), its rest positions and onSurface flags (RestModel; indexed from the
/// body's first vertex) and, for self-contact, its elements. `thickness` is the body's voxel size.
/// Throws std::invalid_argument if the surface is 2D or a corner lies outside [vertexBegin, vertexEnd).
ContactBody buildContactBody(const DisplaySurface& surface, uint32_t vertexBegin, uint32_t vertexEnd, Real thickness,
                             const Vec3* rest, const uint8_t* onSurface, const ElementRows& elements);

/// Closest point on triangle (a, b, c) to p: barycentric weights (sum 1) and the feature it lies
/// on: 0 = inside the face, 1..3 = on an edge (1: ab, 2: bc, 3: ca), 4..6 = at a corner (a, b, c).
struct ClosestPoint {
  std::array<Real, 3> w;
  int feature;
};
ClosestPoint closestPointOnTriangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c);

/// The contact surfaces of a world's bodies: body i (RestModel::bodies[i] of `world`, bodies.h)
/// from its own layout and volume (the voxel display surface), thickness its voxel size.
/// std::invalid_argument if the counts differ from the model's bodies.
std::vector<ContactBody> buildContactBodies(const RestModel& world, const std::vector<const Layout*>& layouts,
                                            const std::vector<const VoxelVolume*>& volumes);

/// A vertex's position at the tracks' last rebuild, rounded to float (x, y, z, 0): half the bytes
/// a step streams to measure how far it has moved since; the stage adds the rounding back.
using RefPoint = std::array<float, 4>;

/// How far a body moved, what the stage's first pass measures (BodyContacts::measure): per axis,
/// the largest square of a vertex's coordinate difference between the end of the step and its
/// start (moved2) and between the end of the step and its RefPoint (since2;
/// BodyContacts::referencePositions()), over every vertex of the body (its surface moves no
/// farther). An explicit step measures it in its own vertex pass, where the positions are at hand
/// (World::stageVertices), and hands it in (BodyContactState::motion).
struct BodyMotion {
  std::array<Real, 3> moved2{0, 0, 0};  ///< [m^2]
  std::array<Real, 3> since2{0, 0, 0};  ///< [m^2]
  void add(const BodyMotion& m) {
    for (int a = 0; a < 3; ++a)
      moved2[size_t(a)] = std::max(moved2[size_t(a)], m.moved2[size_t(a)]),
      since2[size_t(a)] = std::max(since2[size_t(a)], m.since2[size_t(a)]);
  }
};

/// Adds vertices [begin, end) to m: x the end of the step, x0 its start, ref the rebuild's
/// positions (world ids). A NaN difference is left out (max keeps the larger of two numbers).
inline void addMotion(const Vec3* x, const Vec3* x0, const RefPoint* ref, size_t begin, size_t end, BodyMotion& m) {
  for (size_t u = begin; u < end; ++u)
    for (int a = 0; a < 3; ++a) {
      const Real d = x[u][a] - x0[u][a], e = x[u][a] - Real(ref[u][size_t(a)]);
      m.moved2[size_t(a)] = d * d > m.moved2[size_t(a)] ? d * d : m.moved2[size_t(a)];
      m.since2[size_t(a)] = e * e > m.since2[size_t(a)] ? e * e : m.since2[size_t(a)];
    }
}

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

/// What one call found.
struct BodyContactStats {
  size_t candidates = 0;  ///< Vertex lookups in the narrow phase (all rounds).
  /// Of those, lookups of vertices that this stage's own corrections had moved (a contact's vertex
  /// or face corner, pushed out by an earlier round): each must be looked up again, whatever the
  /// bounds, since it ends a correction a skin away from the other body (docs/speed.md, "the floor").
  size_t movedLookups = 0;
  size_t contacts = 0;    ///< Vertex-face contacts resolved.
  Real maxDepth = 0;      ///< [m] deepest vertex found, before correction.
  int rounds = 0;         ///< Detection rounds run.
  int rebuilds = 0;       ///< Times the candidate lists kept across steps were rebuilt (see the header).
  int takeBacks = 0;      ///< Times the last resort took bodies back towards the step's start (0: not needed).
  size_t warm = 0;        ///< Contacts of the last stage that the warm start applied (found inside their plane).
  Real takenBackTo = 1;   ///< [-] the fraction of the step's motion the taken-back bodies kept.
  /// "Inside" findings deeper than the step's motion can reach that the winding number of the
  /// other body's surface said were outside (a folded surface misleads the pseudo-normal test):
  /// dropped, not pushed (dropUnreachable).
  size_t unreachable = 0;
  double seconds = 0;     ///< Wall time of the call (measurements; no result depends on it).
};

/// The stage: contact surfaces of the bodies and the per-step scratch.
class BodyContacts {
 public:
  BodyContacts() = default;
  BodyContacts(std::vector<ContactBody> bodies, const BodyContactSettings& settings);

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
  void setWarmStart(bool warm) { warmStart_ = warm, warm_.clear(), warmAt_.clear(); }
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
  // Some faces of one body in a dense table of cubic cells over the box they fill (buildGrid),
  // cell (i, j, k) at index (k dims[1] + j) dims[0] + i. Each listed face has a box that holds
  // it: its box at the build, grown by how far its corners may move before the grid is rebuilt
  // (a pair's track), or by nothing (a grid for one query pass).
  struct Grid {
    Box box;  ///< The listed faces' boxes within the region: a query box missing it finds none.
    Vec3 origin{0, 0, 0};
    Real cell = 1, inv = 1;  ///< [m] edge of a cell, its inverse.
    std::array<int64_t, 3> dims{0, 0, 0};
    size_t count = 0;             ///< Cells (0: no face listed).
    std::vector<uint32_t> tri;    ///< The listed faces' triangle ids, in listing order.
    std::vector<Box> triBox;      ///< Their boxes (see above).
    std::vector<Box> now;         ///< A track's: their boxes at the positions of the round (the queries' pruning).
    std::vector<uint32_t> start;  ///< Per cell: its faces at items[start[c] .. start[c + 1]).
    std::vector<uint32_t> items;  ///< Indices into tri.
    std::vector<Box> cellBox;     ///< Per cell: its faces' boxes clipped to it (see buildGrid).
    std::array<std::vector<Real>, 3> cellLo,
        cellHi;                  ///< Per axis and cell: its edges, grown by a rounding slack (outer cells: +-inf).
    std::vector<uint32_t> fill;  ///< Scratch of the build.
    std::vector<std::array<int32_t, 6>> range;  ///< Scratch of the build: each face's cell range.
    int64_t cellOf(Real v, int a) const;        ///< Clamped into the table.
    bool rangeOf(const Vec3& lo, const Vec3& hi, std::array<int64_t, 6>& c) const;
  };
  // A pair of bodies across steps (ordered: a's vertices against b's faces), valid until either
  // body's surface moved farther than loose_ from where it was at the rebuild (sinceRebuild_) or a
  // step's search radius exceeds rCap_ (then every track is rebuilt).
  struct Track {
    Grid grid;  ///< b's faces that can come within rCap_ of a vertex of a before then.
    std::vector<uint32_t>
        vertices;  ///< a's vertices that can come within rCap_ of one of them (indices into `vertices`).
    std::vector<Real>
        clearance;  ///< Per candidate: its distance to b's surface at its last check was at least this (< 0: look).
    std::vector<Vec3> checkedAt;         ///< Per candidate: where it was then.
    std::vector<Real> faceDrift;         ///< Per candidate: how far b's surface had moved from the rebuild then.
    std::vector<Real> faceCorrected;     ///< Per candidate: how far the stage's corrections had moved b's surface then.
    std::vector<uint32_t> checkedStage;  ///< Per candidate: the stage (resolve call) of its last check.
    std::vector<uint8_t> checkedRound;   ///< Per candidate: the round of that stage.
    // Per candidate, what a round's local bound found (preparePair, shiftCells): outside, at least
    // roundClearance from b's surface at roundAt, in round roundOf of stage roundStage.
    std::vector<Real> roundClearance;
    std::vector<Vec3> roundAt;
    std::vector<uint32_t> roundStage;
    std::vector<uint8_t> roundOf;
    std::vector<uint32_t> nearest;  ///< Per vertex of a (index into `vertices`): its nearest face of b and its nearest
                                    ///< facing face (detectVertex) when last found (kNone: none).
  };
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
                   const Vec3* x, Contact* out, Real* clearance, uint32_t* hint) const;
  struct Nearest {
    Real d2;       ///< [m^2] squared distance to it (reach^2 when none).
    uint32_t tri;  ///< Its id, or kNone.
    ClosestPoint cp;
  };
  template <class Accept>
  Nearest nearestTriangle(const Grid& g, const ContactBody& faces, const Vec3& p, Real reach, const Vec3* x,
                          uint32_t hint, Accept&& accept) const;
  Nearest nearestTriangle(const Grid& g, const ContactBody& faces, const Vec3& p, Real reach, const Vec3* x,
                          uint32_t hint = ContactBody::kNone) const;
  void updatePatches(const Vec3* x);
  void markTouched(const Contact& c, const Vec3* x);

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
  std::vector<Vec3> entry_;  ///< Per contact: its relative velocity when the velocity response began.
  // The warm start (header): the last stage's body-body contacts and where their vertex and face
  // corners ended it (4 per contact); used only where the step started there (previousPositions).
  bool warmStart_ = true;
  std::vector<Contact> warm_;
  std::vector<Vec3> warmAt_;
  std::vector<std::pair<std::array<uint32_t, 4>, uint32_t>> warmKeys_;  ///< Scratch of keepWarm: (vertex, face), index.
  bool applyWarm(const BodyContactState& s, BodyContactStats& stats);
  void keepWarm(const Vec3* x);
  Grid grid_;                          ///< For one pass (self-contact, proximity).
  std::vector<QueryScratch> scratch_;  ///< Per member (one when serial).
  ThreadTeam* team_ = nullptr;
  uint32_t minParallel_ = kMinParallel;
  std::vector<Contact> slot_;        ///< Per entry of looked_: its contact, if any.
  std::vector<uint8_t> slotState_;   ///< Per vertex: detectVertex's answer (0: skipped).
  std::vector<uint32_t> looked_;     ///< The pass's candidates to look up (indices into their pair's track).
  std::vector<uint32_t> lookedJob_;  ///< Per entry of looked_: its pair (index into jobs_).
  std::vector<PairJob> jobs_;        ///< The pass's pairs, in order.
  std::vector<std::array<uint32_t, 2>> boxChunks_;  ///< The pass's chunks of faces' boxes now: (job, first face).
  std::vector<uint8_t> pick_;                       ///< Per (vertex body, face body): detected in this pass.
  std::vector<uint8_t> active_;                     ///< Per (vertex body, face body): contacts in the last round.
  std::vector<uint8_t> movedBodies_;                ///< Per body: a correction of the last round moved its vertices.
};

/// Winding number of a closed triangle surface (world ids into x) about p: 1 inside, 0 outside
/// (the sum of the faces' signed solid angles / 4 pi). Exact for any surface, O(faces): for tests
/// and measurements, not the step.
Real windingNumber(const Vec3& p, const std::vector<std::array<uint32_t, 3>>& triangles, const Vec3* x);

}  // namespace gradel
