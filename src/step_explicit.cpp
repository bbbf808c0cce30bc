// The explicit integrators' advance (symplectic and forward Euler): the element frames (eq. 1)
// and the fused vertex pass (forces, eqs. 2-3, obstacle contacts, the body contacts' start and
// motion), on the thread team in chunks or on this thread; and the team itself.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <type_traits>
#ifdef GRADEL_WITH_OPENMP
#include <omp.h>
#endif

#include "gradel/rotation_fit.h"
#include "step_context.h"
#include "team_chunks.h"

namespace gradel {

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
    if (s.shape == ManipulatorShape::Blade) {  // no contact: an empty bound, never near a vertex
      d4 lo = splat(inf), hi = splat(-inf);
      lo[3] = -inf, hi[3] = inf;
      b.lo.push_back(lo), b.hi.push_back(hi);
      continue;
    }
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
// manipulator's swept bounds skips the contact tests; the others keep their impulses in the
// team member's list of touched blocks (scratch_->touched[member]). Returns the deepest contact [m].
Real World::stageVertices(size_t begin, size_t end, const ContactBounds* cb, int member) {
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
  // One loop per integrator, per "contacts possible" and per "soft-soft contact on": none of
  // these tests is made per vertex, and without contacts nothing is kept for them.
  auto run = [&](auto forward, auto contacts, auto perVertexDamping, auto soft) {
    // The loop's values as locals of this function (the captures are references: a store of a
    // position could alias them, and they were reloaded per vertex).
    Vec3* const xs = positions;
    Vec3* const vs = velocities;
    const Real* const im = invMass;
    const Real* const vdamp = vertexDamp;
    const Real h = dt, c = damp;
    const d4 gravity = g;
    d4 start[kBlock], startVelocity[kBlock];
    for (size_t b = begin, be; b < end; b = be) {
      be = std::min(end, (b / kBlock + 1) * kBlock);  // blocks aligned to kBlock (the contact forces' partial sums)
      d4 lo = splat(std::numeric_limits<Real>::infinity()), hi = -lo;
      d4 moved2 = splat(0), since2 = splat(0);  // (addMotion, lane per axis, from the values at hand)
      bool touched = false;
      gatherVertexForces(m, *stageRest_, scratch_->frames.data(), b, be, [&](size_t i, d4 partial, Real k) {
        const d4 x0 = loadVec3(xs[i]), v0 = loadVec3(vs[i]);
        const d4 force = partial - k * x0;
        const d4 a = force * im[i] + gravity;
        if constexpr (soft()) storeVec3(startX[i], x0), storeVec3(startV[i], v0);
        d4 x = x0, v = v0;
        Real vd = c;
        if constexpr (perVertexDamping()) vd = vdamp[i];
        if constexpr (forward())
          forwardEulerStep(x, v, a, h, vd);  // integration.h
        else
          symplecticEulerStep(x, v, a, h, vd);
        storeVec3(xs[i], x), storeVec3(vs[i], v);
        if constexpr (soft()) {
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
          StepContext::TouchedBlocks& list = scratch_->touched[size_t(member)];
          list.block.push_back(uint32_t(b / kBlock));
          list.work.push_back(0);
          list.impulse.resize(list.impulse.size() + surfaces, ContactForce{});
          ContactForce* impulse = &list.impulse[list.impulse.size() - surfaces];
          Real& work = list.work.back();
          for (size_t i = b; i < be; ++i) {
            Vec3 previous, previousVelocity;
            storeVec3(previous, start[i - b]), storeVec3(previousVelocity, startVelocity[i - b]);
            depth = std::max(depth, resolveVertexContacts(previous, previousVelocity, positions[i], velocities[i],
                                                          m.mass[i], vertexStiffness_[i], impulse, &work));
          }
        }
      }
      if constexpr (soft()) {
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
    auto runSoft = [&](auto damped) {
      bodyContacts_ ? run(forward, contacts, damped, Yes{}) : run(forward, contacts, damped, No{});
    };
    vertexDamp ? runSoft(Yes{}) : runSoft(No{});
  };
  if (sim_.integrator == IntegratorKind::ForwardEuler)
    cb ? runDamped(Yes{}, Yes{}) : runDamped(Yes{}, No{});
  else
    cb ? runDamped(No{}, Yes{}) : runDamped(No{}, No{});
  return depth;
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
// Chunks handed out by the team: ~20-40 us of work each (kElementChunk, the longest element chunk,
// a multiple of the rotation fit's lanes; kVertexChunk of stageVertices' blocks).
constexpr size_t kElementChunk = 256, kVertexChunk = 512;
static_assert(kVertexChunk % kVertexBlock == 0, "chunks hold whole blocks (the contact forces' partial sums)");
static_assert(kVertexBlock % kVertexStartStride == 0, "the vertex splits are made on the stage's blocks");
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
  // Vertices by blocks of kVertexStartStride (the stage keeps each block's start in its frame list).
  vertexSplit_ = chunkSplit(stageRest_->vertexBlockStart, kVertexCost * kVertexStartStride, members,
                            kVertexChunk / kVertexStartStride);
  // Each element batch to the member whose vertex share holds its first vertex (team_chunks.h): on a
  // machine whose cores share no cache, a frame or position the other core wrote is a transfer
  // between them (docs/speed.md, "A leaner step", sixth pass).
  std::vector<size_t> vertexBound(size_t(members) + 1);
  for (size_t t = 0; t <= size_t(members); ++t)
    vertexBound[t] = std::min(model_->numVertices(), vertexSplit_[t] * kVertexChunk);
  elementChunks_ = ownerElementChunks(*model_, vertexBound, kRotationLanes, kElementChunk, elementSplit_);
  memberContactDepth_.assign(size_t(members), 0.0);
  teamMembers_ = members;
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

ThreadTeam* World::estimateTeam(std::unique_ptr<ThreadTeam>& local) const {
  const int members = stepMembers();
  // One thread when the step's governor found one faster on this machine now (a busy machine:
  // thread_team.h), as the step does.
  if (members == 1 || (governor_ && governor_->usingOne())) return nullptr;
  if (team_ && team_->ownedByCaller() && team_->members() == members) return team_.get();
  local = std::make_unique<ThreadTeam>(members);
  return local.get();
}

void World::stepExplicit() {
  const size_t V = model_->numVertices(), E = model_->numElements();
  const int members = stepMembers();
  moveManipulators(state_.time + dt_);  // the elements do not see them; the contacts see t + dt
  const bool contacts = !manipulators_.empty() || domain_.enabled;
  ContactBounds bounds;
  if (contacts) bounds = contactBounds();
  const ContactBounds* cb = contacts ? &bounds : nullptr;
  if (scratch_->touched.size() < size_t(members)) scratch_->touched.resize(size_t(members));
  auto runOnThisThread = [&] {
    stageElementFrames(0, E);
    scratch_->maxContactDepth = stageVertices(0, V, cb, 0);
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
      auto vertexSplit = [&](int k) {  // by blocks of kVertexStartStride, as prepareTeam
        return std::min(V, kVertexStartStride * splitPoint(stageRest_->vertexBlockStart, kVertexCost * kVertexStartStride,
                                                           k, T, kVertexBlock / kVertexStartStride));
      };
      depth = stageVertices(vertexSplit(t), vertexSplit(t + 1), cb, t);
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
        while (elementQueue_->claim(t, &c)) stageElementFrames(elementChunks_[c].first, elementChunks_[c].second);
        team_->barrier();
        Real depth = 0;
        while (vertexQueue_->claim(t, &c))
          depth = std::max(depth, stageVertices(c * kVertexChunk, std::min(V, (c + 1) * kVertexChunk), cb, t));
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

}  // namespace gradel
