#include "gradel/projective.h"

#include <Eigen/Dense>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>

#include "factor_solve.h"
#include "gradel/element.h"
#include "gradel/integration.h"
#include "gradel/rotation_fit.h"

#if GRADEL_WITH_METIS
#include <iostream>  // Eigen 3.4's MetisSupport uses std::cerr without including it
// clang-format off
#include <Eigen/MetisSupport>
// clang-format on
#endif

namespace gradel {

using SpMat = Eigen::SparseMatrix<Real>;
// The factor's fill-reducing ordering: nested dissection (METIS) where the build has it, else
// Eigen's default AMD. On the 64-voxel box (17,219 rows, coarse elements of up to 34 vertices) L
// has 2.5 M entries against 4.3 M, and is factored 2.3x faster (CMakeLists.txt, GRADEL_METIS).
#if GRADEL_WITH_METIS
using FactorOrdering = Eigen::MetisOrdering<SpMat::StorageIndex>;
#else
using FactorOrdering = Eigen::AMDOrdering<SpMat::StorageIndex>;
#endif
using Rhs = Eigen::Matrix<Real, Eigen::Dynamic, 3>;

namespace {

// The matrix of determinant 1 nearest F (Frobenius norm): F = U diag(s) V^T with the signs of
// an inverted F folded into the smallest singular value, then s' = argmin |s' - s| with
// prod s' = 1 by Newton steps on the linearised constraint (Bouaziz et al. 2014, sec. 5). 2D: the
// x-y block (F_zz = 1 stays).
Mat3 nearestUnitDeterminant(int dim, const Mat3& F) {
  const int D = dim == 2 ? 2 : 3;
  const Eigen::MatrixXd Fd = F.topLeftCorner(D, D);
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(Fd, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::MatrixXd U = svd.matrixU(), V = svd.matrixV();
  Eigen::VectorXd s = svd.singularValues();
  if (U.determinant() * V.determinant() < 0) s(D - 1) = -s(D - 1), U.col(D - 1) = -U.col(D - 1);
  Eigen::VectorXd t = s;
  for (int it = 0; it < 8; ++it) {
    Eigen::VectorXd g(D);
    Real c = 1;
    for (int k = 0; k < D; ++k) c *= t(k);
    for (int k = 0; k < D; ++k) {
      g(k) = 1;
      for (int l = 0; l < D; ++l)
        if (l != k) g(k) *= t(l);
    }
    const Real gg = g.squaredNorm();
    if (!(gg > 1e-300)) break;
    // The point of the constraint's tangent plane at t nearest s.
    t = s - g * ((c - 1) + g.dot(s - t)) / gg;
  }
  Mat3 T = Mat3::Identity();
  T.topLeftCorner(D, D) = U * t.asDiagonal() * V.transpose();
  return T;
}

}  // namespace

struct ProjectiveSolver::Impl {
  const RestModel* model = nullptr;
  Real dt = 0;                        ///< [s]; 0 = static solver (no inertia term).
  std::vector<int32_t> freeIndex;     ///< Per vertex: row in the reduced system, -1 if pinned.
  std::vector<uint32_t> vertexOfRow;  ///< Per row of the reduced system: its vertex.
  std::vector<uint32_t> pinned;       ///< Pinned vertex ids (ascending).
  std::vector<Real> diagonal;         ///< Per vertex: the global matrix's diagonal entry (0 if pinned).
  SplitFactor factor;                 ///< The reduced global matrix's LDL^T factor (factor_solve.h).
  ThreadTeam* team = nullptr;         ///< Its solves' threads (null: this thread).
  Rhs rhs, sol;                       ///< Scratch, numFree x 3.
  /// Per element, the volume constraint's weight w_e (0: none) and S_e^-1 (projective.h); empty
  /// without a volumetric term.
  std::vector<Real> volumeWeight;
  std::vector<Mat3> restInverse;
  mutable std::vector<Vec3> rows;  ///< Scratch of factorSolve, numFree.

  // z = A^-1 b through the factor A = P^T L D L^T P, the three coordinates at once: each
  // triangular sweep reads L once for all three (Eigen's solve sweeps it once per column, and the
  // sweeps are bound by reading L: 3x the time on the 64-voxel box), split between two threads
  // along the elimination tree (factor_solve.h). Row i of b is get(i); put(i, z_i) receives the
  // solution.
  template <class Get, class Put>
  void factorSolve(Get&& get, Put&& put) const {
    const size_t n = vertexOfRow.size();
    if (n == 0) return;  // every vertex pinned: nothing to solve
    rows.resize(n);
    for (size_t i = 0; i < n; ++i) rows[i] = get(Eigen::Index(i));
    factor.solve(rows.data(), rows.data(), team);
    for (size_t i = 0; i < n; ++i) put(Eigen::Index(i), rows[i]);
  }
  Rhs solve(const Rhs& b) const {
    Rhs z(b.rows(), 3);
    factorSolve([&](Eigen::Index i) { return Vec3(b.row(i).transpose()); },
                [&](Eigen::Index i, const Vec3& v) { z.row(i) = v.transpose(); });
    return z;
  }

  // Local step for every element, and the right-hand side sum_e k_e G_e^T (M_e R0) plus the
  // pinned vertices' coupling k_e/n sum_{pinned b in e} x_b (the -A_fp x_p term), added into rhs.
  void addElementTerms(const std::vector<Vec3>& x, std::vector<Quat>& q, int rotationIterations) {
    const RestModel& m = *model;
    std::vector<Vec3> p, offsets;
    for (size_t e = 0; e < m.numElements(); ++e) {
      const uint32_t b = m.elemStart[e], n = m.elemStart[e + 1] - b;
      const uint32_t* verts = &m.elemVerts[b];
      const Vec3* R0 = m.restOffsets(e, offsets);
      const Mat3 A = elementCovariance(x.data(), verts, R0, int(n));
      if (m.dim == 2)
        q[e] = Quat(Eigen::AngleAxisd(fitRotation2(A), Vec3::UnitZ()));
      else
        fitRotation3(A, q[e], rotationIterations, 1e-12);
      const Mat3 M = q[e].toRotationMatrix();
      const Real k = m.stiffness[e];
      p.resize(n);
      Vec3 mean = Vec3::Zero(), pinnedSum = Vec3::Zero();
      for (uint32_t i = 0; i < n; ++i) {
        p[i] = M * R0[i];
        mean += p[i];
        if (freeIndex[verts[i]] < 0) pinnedSum += x[verts[i]];
      }
      mean /= Real(n);
      const Vec3 coupling = k / Real(n) * pinnedSum;
      for (uint32_t i = 0; i < n; ++i) {
        const int32_t r = freeIndex[verts[i]];
        if (r < 0) continue;
        rhs.row(r) += (k * (p[i] - mean) + coupling).transpose();
      }
      if (!volumeWeight.empty() && volumeWeight[e] > 0) addVolumeTerms(e, x, A, R0);
    }
  }

  // The volume constraint of element e (projective.h): T = the matrix of determinant 1 nearest
  // F = A S^-1, and the right-hand side w T R0_i minus the pinned vertices' coupling
  // w sum_{pinned k} (R0_i^T S^-1 R0_k) x_k. R0: the element's rest offsets.
  void addVolumeTerms(size_t e, const std::vector<Vec3>& x, const Mat3& A, const Vec3* R0) {
    const RestModel& m = *model;
    const uint32_t b = m.elemStart[e], n = m.elemStart[e + 1] - b;
    const uint32_t* verts = &m.elemVerts[b];
    const Mat3& Sinv = restInverse[e];
    const Real w = volumeWeight[e];
    const Mat3 T = nearestUnitDeterminant(m.dim, elementDeformationGradient(m.dim, A, Sinv));
    for (uint32_t i = 0; i < n; ++i) {
      const int32_t r = freeIndex[verts[i]];
      if (r < 0) continue;
      Vec3 t = w * (T * R0[i]);
      for (uint32_t k = 0; k < n; ++k)
        if (freeIndex[verts[k]] < 0) t -= w * R0[i].dot(Sinv * R0[k]) * x[verts[k]];
      rhs.row(r) += t.transpose();
    }
  }

  // Held vertices: rows of the reduced system and their targets. The global solve with them
  // held is a filtered PCG (Baraff and Witkin 1998) on the free rows, preconditioned by the factor
  // with the held rows zeroed (z = S A^-1 S r), warm-started from the current positions: no work
  // per held vertex beyond zeroing its rows, where the capacitance matrix of the held set cost one
  // back-solve per held vertex and a dense |held|^2 matrix (1.3 GB for the 64-voxel box's floor).
  SpMat A;  ///< The reduced global matrix (for the PCG's products).
  std::vector<int32_t> heldRows;
  Rhs heldTargets;
  std::vector<Vec3> heldNormals;     ///< Per held row (empty: two-sided holds).
  std::vector<char> heldSlides;      ///< Per held row: held along its normal only (slides).
  std::vector<uint32_t> heldSource;  ///< Per held row: its index in step()'s `held`.
  // PCG iterations per global solve, at most, and the fall of r.z (per coordinate) that stops them
  // sooner. At 2 iterations (before) the stiff ball of grasp-body at E x1000 and dt = 1/30 s
  // ended its first step on the floor with 31 J of elastic energy (the explicit run's peak of the
  // whole grasp: 42 J) and the run exited 3; the solve converges in 3-6 (0.0043 J). With the
  // tolerance at 1e-12 rather than 1e-6 the scenes of bench/large_energy.py end within 1 % of
  // the same peaks and the grasp-wall scene takes 20 % longer.
  static constexpr int kHeldIterations = 8;
  static constexpr Real kHeldTolerance = 1e-6;

  // Every hold of the step (the held rows above are those in place in this pass), in step()'s order.
  struct Hold {
    int32_t row;      ///< Its row of the reduced system.
    Vec3 target;      ///< Where it holds its vertex.
    Vec3 normal;      ///< The surface's outward normal (zero: two-sided holds).
    char slides;      ///< Held along its normal only.
    uint32_t source;  ///< Its index in step()'s `held`.
    char active;      ///< In place in this pass (updateHolds).
    Real friction;    ///< A sticking hold's Coulomb coefficient (0: no limit on its tangential force).
    Vec3 anchor;      ///< Where it sticks (its target before any slip).
    uint32_t body;    ///< Its vertex's body.
    Vec3 carried;     ///< Its body's slip (bodySlip) on its tangent plane, in its target.
  };
  std::vector<Hold> holds;
  // Per body: the common slip of its holds with a cone (updateHolds), the mass of its free
  // vertices, and whether it has pinned ones (then no common slip).
  std::vector<Vec3> bodySlip;
  std::vector<Real> bodyMass;
  std::vector<char> bodyPinned;

  void prepareHeld(const std::vector<uint32_t>& held, const std::vector<Vec3>& targets,
                   const std::vector<Vec3>& normals, const std::vector<Real>& friction,
                   const std::vector<char>& letGo, const std::vector<Vec3>& slip) {
    holds.clear();
    for (size_t j = 0; j < held.size(); ++j) {
      if (freeIndex.at(held[j]) < 0) continue;
      // A frictionless surface holds its vertex along the normal only: it slides.
      const bool slides = !normals.empty() && !friction.empty() && !(friction.at(j) > 0);
      // Coulomb's cone (updateHolds) on a sticking hold with friction and a normal.
      const Real mu = !normals.empty() && !friction.empty() && !slides && std::isfinite(friction.at(j))
                          ? friction.at(j)
                          : Real(0);
      const Vec3 n = normals.empty() ? Vec3::Zero() : normals.at(j);
      const Vec3 guess = mu > 0 && !slip.empty() ? Vec3(slip.at(j) - slip.at(j).dot(n) * n) : Vec3::Zero();
      holds.push_back({freeIndex[held[j]], targets[j] + guess, n, char(slides), uint32_t(j),
                       char(normals.empty() || letGo.empty() || !letGo.at(j)), mu, targets[j],
                       uint32_t(model->bodyOfVertex(held[j])), Vec3::Zero()});
    }
    const RestModel& m = *model;
    bodySlip.assign(m.numBodies(), Vec3::Zero()), bodyMass.assign(m.numBodies(), 0);
    bodyPinned.assign(m.numBodies(), 0);
    if (!holds.empty())
      for (size_t i = 0; i < m.numVertices(); ++i) {
        const size_t b = m.bodyOfVertex(i);
        if (freeIndex[i] >= 0)
          bodyMass[b] += m.mass[i];
        else
          bodyPinned[b] = 1;
      }
    twoSided = normals.empty();
    gatherHeld();
  }
  bool twoSided = true;  ///< No normals given: the holds are never let go.
  // The held rows of this pass: the holds in place, in order.
  void gatherHeld() {
    heldRows.clear(), heldNormals.clear(), heldSlides.clear(), heldSource.clear();
    size_t n = 0;
    for (const Hold& h : holds) n += h.active ? 1 : 0;
    heldTargets.resize(Eigen::Index(n), 3);
    for (const Hold& h : holds) {
      if (!h.active) continue;
      heldTargets.row(Eigen::Index(heldRows.size())) = h.target.transpose();
      heldRows.push_back(h.row), heldSlides.push_back(h.slides), heldSource.push_back(h.source);
      if (!twoSided) heldNormals.push_back(h.normal);
    }
  }

  // Pair constraints (contacts between bodies, projective.h): per pair its k, and the pairs
  // active in this pass (lambda + k (gap - c(x)) > 0 at the pass's start).
  std::vector<PairConstraint>* pairs = nullptr;
  std::vector<Real> pairK;
  std::vector<char> bodyInPair;  ///< Per body: a vertex of it in a pair (no common slip, updateHolds).
  std::vector<uint32_t> activePairs;
  static constexpr int kPairIterations = 8;      ///< PCG iterations per global solve with active pairs.
  static constexpr Real kPairTolerance = 1e-12;  ///< Stop when r.z has fallen by this factor.
  // k = kPairStiffness x the pair's effective mass / dt^2 (projective.h). At 1 a contact vertex
  // held by a stiff body (whose inertia, not its own mass, resists the push) closed only a few
  // per cent of its violation per pass: two balls closing at 1 m/s ended their first contact
  // step 8 mm inside each other (two-balls.json, dt = 1/60 s, 10 passes); at 10, 1.5 mm (14 mm
  // closing at 10 m/s, which the post-step stage clears); at 30 the 8 PCG iterations no longer
  // converge and the balls closing at 10 m/s ended steps a voxel inside (measured).
  static constexpr Real kPairStiffness = 10;
  // ... and at least kPairDiagonalShare / (J D^-1 J^T) (D: the global matrix's diagonal, which
  // holds the elements' stiffness): for a stiff body the inertial k is far below what a push
  // needs (grasp-body at E x100, dt = 1/60 s: 4-90 N/m against elements of ~1e5 N/m; lambda grew
  // ~11 N over a step, the ball ended steps ~1 cm inside the block and the body-contact stage
  // pushed it out with 36 J at once). At 1 the stack of stack.json sank through itself (top
  // 0.060 m against the explicit 0.178 m) and at 0.3 it still ended steps with vertices inside
  // other bodies: the 8 PCG iterations, preconditioned without the pairs, stop short and the
  // multipliers' updates overshoot; at 0.1 the stack and the fast balls keep their figures.
  static constexpr Real kPairDiagonalShare = 0.1;

  // n . (x_p - sum w_k x_k) over the free (or, pinnedOnly, the pinned) vertices of the pair.
  Real pairValue(const PairConstraint& c, const std::vector<Vec3>& x, bool pinnedOnly) const {
    Real v = 0;
    if ((freeIndex[c.vertex] < 0) == pinnedOnly) v += c.n.dot(x[c.vertex]);
    for (int k = 0; k < 3; ++k)
      if ((freeIndex[c.face[size_t(k)]] < 0) == pinnedOnly) v -= c.w[size_t(k)] * c.n.dot(x[c.face[size_t(k)]]);
    return v;
  }
  // J y on the reduced rows, and out += s J^T.
  Real pairRow(const PairConstraint& c, const Rhs& y) const {
    Real v = 0;
    if (freeIndex[c.vertex] >= 0) v += y.row(freeIndex[c.vertex]).dot(c.n.transpose());
    for (int k = 0; k < 3; ++k)
      if (const int32_t r = freeIndex[c.face[size_t(k)]]; r >= 0) v -= c.w[size_t(k)] * y.row(r).dot(c.n.transpose());
    return v;
  }
  void addPairT(const PairConstraint& c, Real s, Rhs& out) const {
    if (freeIndex[c.vertex] >= 0) out.row(freeIndex[c.vertex]) += s * c.n.transpose();
    for (int k = 0; k < 3; ++k)
      if (const int32_t r = freeIndex[c.face[size_t(k)]]; r >= 0) out.row(r) -= s * c.w[size_t(k)] * c.n.transpose();
  }
  // The matrix with the active pairs: (A + sum k J^T J) y.
  Rhs apply(const Rhs& y) const {
    Rhs out = A * y;
    for (uint32_t j : activePairs) addPairT((*pairs)[j], pairK[j] * pairRow((*pairs)[j], y), out);
    return out;
  }
  void preparePairs(std::vector<PairConstraint>* p) {
    pairs = p && !p->empty() ? p : nullptr;
    pairK.clear(), activePairs.clear();
    bodyInPair.assign(model->numBodies(), 0);
    if (!pairs) return;
    const RestModel& m = *model;
    for (const PairConstraint& c : *pairs) {
      Real W = freeIndex.at(c.vertex) >= 0 ? m.invMass[c.vertex] : 0;
      Real Dinv = freeIndex.at(c.vertex) >= 0 ? 1 / diagonal[c.vertex] : 0;
      bodyInPair.at(m.bodyOfVertex(c.vertex)) = 1;
      for (int k = 0; k < 3; ++k) {
        const uint32_t f = c.face[size_t(k)];
        bodyInPair.at(m.bodyOfVertex(f)) = 1;
        if (freeIndex.at(f) < 0) continue;
        W += c.w[size_t(k)] * c.w[size_t(k)] * m.invMass[f];
        Dinv += c.w[size_t(k)] * c.w[size_t(k)] / diagonal[f];
      }
      pairK.push_back(W > 0 && dt > 0 ? std::max(kPairStiffness / (dt * dt * W), kPairDiagonalShare / Dinv) : 0);
    }
  }
  // The pass's active pairs and their right-hand side J^T (lambda + k (gap - c_pinned)).
  void addPairTerms(const std::vector<Vec3>& x) {
    activePairs.clear();
    if (!pairs) return;
    for (uint32_t j = 0; j < pairs->size(); ++j) {
      const PairConstraint& c = (*pairs)[j];
      if (!(pairK[j] > 0)) continue;
      const Real pinnedPart = pairValue(c, x, true);
      if (!(c.lambda + pairK[j] * (c.gap - pinnedPart - pairValue(c, x, false)) > 0)) continue;
      activePairs.push_back(j);
      addPairT(c, c.lambda + pairK[j] * (c.gap - pinnedPart), rhs);
    }
  }
  // The multipliers after a pass: lambda <- max(0, lambda + k (gap - c(x))).
  void updatePairs(const std::vector<Vec3>& x) {
    if (!pairs) return;
    for (uint32_t j = 0; j < pairs->size(); ++j) {
      PairConstraint& c = (*pairs)[j];
      c.lambda = std::max(Real(0), c.lambda + pairK[j] * (c.gap - pairValue(c, x, true) - pairValue(c, x, false)));
    }
  }

  // The reaction of held row r, A x - b on the row (the force the hold exerts); with active pairs
  // A is A + sum k J^T J, whose product with sol is Asol = appliedWithPairs() (else unused).
  Rhs appliedWithPairs() const { return activePairs.empty() ? Rhs() : apply(sol); }
  Vec3 heldReaction(int32_t r, const Rhs& Asol) const {
    if (!activePairs.empty()) return Vec3(Asol.row(r).transpose()) - Vec3(rhs.row(r).transpose());
    // Row r of A is column r (A is symmetric): its entries, not a search of every column (A.row(r)
    // of a column-major matrix visits all of them: 78 % of box-realtime's contact steps, with
    // ~4,000 held vertices).
    Vec3 a = Vec3::Zero();
    for (SpMat::InnerIterator it(A, r); it; ++it) a += it.value() * Vec3(sol.row(it.index()).transpose());
    return a - Vec3(rhs.row(r).transpose());
  }

  // One-sided holds, an active set over the step's passes: lets go of the held rows whose reaction
  // (A x - b on the row: the force the hold exerts) points into the surface, and puts back a hold
  // let go earlier whose vertex is now behind its surface's plane (n . (x - target) < 0). Order
  // kept, so the result does not depend on anything but the data. Why both: the reactions come
  // from an inexact solve (kHeldIterations PCG iterations from the last pass's iterate), and early
  // in a step a resting body's supports can show a reaction into the floor of a few newtons
  // against the vertex's weight of a few millinewtons (the grasp-body block at dt = 1/30 s: all 49
  // of its floor holds let go in the first two passes); let go for good, the body fell through the
  // floor for the rest of the step and the last contact pass put its bottom back up a whole
  // step's fall (dt^2 g = 1.1 cm), 2.16 J of elastic energy in one step, 11x the explicit run's
  // peak (issue 26). Put back, the next pass holds it again. A sticking hold with friction slips
  // by Coulomb's cone (projective.h; a hold made to slide freely with the kinetic friction force
  // as a known force once its reaction left the cone let the ball of a stiff grasp slip out and
  // invert elements, issue 26).
  void updateHolds() {
    if (twoSided || holds.empty()) return;
    const Rhs Asol = appliedWithPairs();
    bool changed = false;
    // A whole body sliding (a box on a floor tilted past its friction angle): the return mapping
    // below, with k the row's diagonal, ~1000x the stiffness of that motion, moved it a few per
    // cent of Coulomb's slide per step (0.026 m in 0.5 s at dt = 1/30 s, Coulomb 0.287 m). So a
    // body whose holds in place all share one plane (one flat surface; its holds all have a cone)
    // first slips as a whole by the same return mapping on the sums of its holds' reactions,
    // tangential F and normal N, with k = M / dt^2 (M: its free mass; the stiffness of its
    // common slip S, which only its inertia resists; a pinned body is not moved so): sticks where
    // |F - k S| <= mu N, else slips against it by the excess / k. The return mapping per hold then
    // works about its anchor carried by S. (A body held by several surfaces, a grasped ball, is
    // left out: there its holds' surpluses beyond their cones do not move it as a whole; moved
    // with their sum, the grasps at E x10 blew up. So is a body in a pair constraint, whose holds'
    // reactions balance the other body's push as well: with the common slip of grasp-body's block
    // on its floor, the scene at E x1 and dt = 1/30 s diverged at 60x the explicit peak; without,
    // 0.76x.)
    const size_t B = bodySlip.size();
    std::vector<Vec3> F(B, Vec3::Zero()), plane(B, Vec3::Zero());
    std::vector<Real> N(B, 0), mu(B, 0);
    std::vector<char> one(B, 1);
    std::vector<Vec3> reaction(holds.size(), Vec3::Zero());  // of the holds in place
    for (size_t j = 0; j < holds.size(); ++j) {
      const Hold& h = holds[j];
      if (!h.active) continue;
      const size_t b = h.body;
      if (h.slides || !(h.friction > 0) || (plane[b] != Vec3::Zero() && (plane[b] != h.normal || mu[b] != h.friction)))
        one[b] = 0;
      plane[b] = h.normal, mu[b] = h.friction;
      const Vec3 f = reaction[j] = heldReaction(h.row, Asol);
      const Real fn = f.dot(h.normal);
      F[b] += f - fn * h.normal, N[b] += fn;
    }
    for (size_t b = 0; b < B; ++b) {
      if (!one[b] || bodyInPair[b] || plane[b] == Vec3::Zero() || bodyPinned[b] || !(bodyMass[b] > 0) || !(N[b] > 0))
        continue;
      const Real k = bodyMass[b] / (dt * dt);
      const Vec3 S = bodySlip[b] - bodySlip[b].dot(plane[b]) * plane[b];
      const Vec3 z = F[b] - k * S;
      const Real len = z.norm(), excess = len - mu[b] * N[b];
      bodySlip[b] = excess > 0 && len > 0 ? Vec3(-(excess / (k * len)) * z) : Vec3::Zero();
    }
    for (size_t j = 0; j < holds.size(); ++j) {
      Hold& h = holds[j];
      if (!h.active) {
        if ((Vec3(sol.row(h.row).transpose()) - h.target).dot(h.normal) < 0) h.active = 1, changed = true;
        continue;
      }
      const Vec3& f = reaction[j];
      const Real fn = f.dot(h.normal);
      if (fn < 0) {
        h.active = 0, changed = true;
        continue;
      }
      if (h.slides || !(h.friction > 0)) continue;
      // Coulomb's cone, a return mapping: z = f_t - k s is the tangential reaction the hold would
      // have at its anchor (s: its slip from there, k: the row's diagonal, its stiffness with every
      // other vertex fixed, which overestimates the reaction's change and so never overshoots).
      // Inside the cone (|z| <= mu f_n) it sticks at its anchor; outside, it slips against z by
      // (|z| - mu f_n) / k, where its reaction is mu f_n against its slip. A slip an early pass's
      // inexact reaction asked for is taken back once the reactions say so.
      // Both about the anchor carried by its body's slip.
      const Vec3 slip = h.target - h.anchor - h.carried;
      const Vec3 carried = bodySlip[h.body] - bodySlip[h.body].dot(h.normal) * h.normal;
      const Real k = diagonal[vertexOfRow[size_t(h.row)]];
      const Vec3 z = f - fn * h.normal - k * slip;
      const Real len = z.norm(), excess = len - h.friction * fn;
      const Vec3 anchor = h.anchor + carried;
      const Vec3 target = excess > 0 && len > 0 ? Vec3(anchor - (excess / (k * len)) * z) : anchor;
      h.carried = carried;
      if (target != h.target) h.target = target, changed = true;
    }
    if (changed) gatherHeld();
  }
  bool anySliding() const { return std::find(heldSlides.begin(), heldSlides.end(), 1) != heldSlides.end(); }
  // The filter of the held rows (Baraff and Witkin 1998): a sticking hold's row zeroed, a sliding
  // one's normal component removed.
  void filterHeld(Rhs& m) const {
    for (size_t k = 0; k < heldRows.size(); ++k) {
      auto row = m.row(heldRows[k]);
      if (heldSlides[k])
        row -= row.dot(heldNormals[k].transpose()) * heldNormals[k].transpose();
      else
        row.setZero();
    }
  }
  // The held rows of sol on their holds: a sticking one at its target, a sliding one moved along
  // its normal onto the target's plane.
  void placeHeld() {
    for (size_t k = 0; k < heldRows.size(); ++k) {
      auto row = sol.row(heldRows[k]);
      const auto target = heldTargets.row(Eigen::Index(k));
      if (heldSlides[k])
        row += (target - row).dot(heldNormals[k].transpose()) * heldNormals[k].transpose();
      else
        row = target;
    }
  }

  void solveInto(std::vector<Vec3>& x) {
    if (heldRows.empty() && activePairs.empty()) {
      sol = solve(rhs);
    } else if (!activePairs.empty() || anySliding()) {
      solvePairs(x);
      return;
    } else {
      // The three coordinates are three independent PCGs (per-column step lengths).
      sol.resize(rhs.rows(), 3);
      for (size_t i = 0; i < freeIndex.size(); ++i)
        if (freeIndex[i] >= 0) sol.row(freeIndex[i]) = x[i].transpose();
      auto zeroHeld = [&](Rhs& m) {
        for (int32_t r : heldRows) m.row(r).setZero();
      };
      for (size_t k = 0; k < heldRows.size(); ++k) sol.row(heldRows[k]) = heldTargets.row(Eigen::Index(k));
      Rhs r = rhs - A * sol;
      zeroHeld(r);
      Rhs z = solve(r);
      zeroHeld(z);
      Rhs p = z, Ap;
      Eigen::Array<Real, 1, 3> rz = (r.array() * z.array()).colwise().sum(), rz0 = rz;
      for (int it = 0; it < kHeldIterations && (rz > kHeldTolerance * rz0).any(); ++it) {
        Ap = A * p;
        const Eigen::Array<Real, 1, 3> pAp = (p.array() * Ap.array()).colwise().sum();
        const Eigen::Array<Real, 1, 3> alpha = (pAp > 0).select(rz / pAp, 0.0);
        sol += (p.array().rowwise() * alpha).matrix();
        r -= (Ap.array().rowwise() * alpha).matrix();
        zeroHeld(r);
        z = solve(r);
        zeroHeld(z);
        const Eigen::Array<Real, 1, 3> rzNew = (r.array() * z.array()).colwise().sum();
        const Eigen::Array<Real, 1, 3> beta = (rz > 0).select(rzNew / rz, 0.0);
        rz = rzNew;
        p = z + (p.array().rowwise() * beta).matrix();
      }
    }
    for (size_t i = 0; i < freeIndex.size(); ++i)
      if (freeIndex[i] >= 0) x[i] = sol.row(freeIndex[i]).transpose();
  }

  // The global solve with active pairs or sliding holds (and any holds): the filtered PCG on
  // A + sum k J^T J, one CG over the three coordinates (the pairs and the sliding holds' filters
  // couple them through n n^T), preconditioned by the
  // factor of A. Without holds or pins the warm start is first shifted by a translation that
  // zeroes each coordinate's residual sum (A 1 = M 1 / dt^2, J 1 = 0): the CG then keeps it at
  // zero, so the solve keeps linear momentum whatever the iteration count.
  void solvePairs(std::vector<Vec3>& x) {
    sol.resize(rhs.rows(), 3);
    for (size_t i = 0; i < freeIndex.size(); ++i)
      if (freeIndex[i] >= 0) sol.row(freeIndex[i]) = x[i].transpose();
    placeHeld();
    auto zeroHeld = [&](Rhs& m) { filterHeld(m); };
    Rhs r = rhs - apply(sol);
    if (heldRows.empty() && pinned.empty() && dt > 0) {
      Real massSum = 0;
      for (size_t i = 0; i < freeIndex.size(); ++i) massSum += model->mass[i];
      const Eigen::Matrix<Real, 1, 3> shift = r.colwise().sum() * (dt * dt / massSum);
      sol.rowwise() += shift;
      for (size_t i = 0; i < freeIndex.size(); ++i) r.row(freeIndex[i]) -= model->mass[i] / (dt * dt) * shift;
    }
    zeroHeld(r);
    Rhs z = solve(r);
    zeroHeld(z);
    Rhs p = z, Ap;
    Real rz = (r.array() * z.array()).sum();
    const Real rz0 = rz;
    for (int it = 0; it < kPairIterations && rz > kPairTolerance * rz0; ++it) {
      Ap = apply(p);
      zeroHeld(Ap);
      const Real pAp = (p.array() * Ap.array()).sum();
      if (!(pAp > 0)) break;
      const Real alpha = rz / pAp;
      sol += alpha * p;
      r -= alpha * Ap;
      z = solve(r);
      zeroHeld(z);
      const Real rzNew = (r.array() * z.array()).sum();
      p = z + (rzNew / rz) * p;
      rz = rzNew;
    }
    for (size_t i = 0; i < freeIndex.size(); ++i)
      if (freeIndex[i] >= 0) x[i] = sol.row(freeIndex[i]).transpose();
  }
};

ProjectiveSolver::ProjectiveSolver(const RestModel& model, Real dt, const std::vector<uint32_t>& pinned)
    : impl_(std::make_unique<Impl>()) {
  Impl& s = *impl_;
  s.model = &model;
  s.dt = dt;
  s.pinned = pinned;
  const size_t V = model.numVertices();
  s.freeIndex.assign(V, 0);
  for (uint32_t i : pinned) s.freeIndex.at(i) = -1;
  int32_t nFree = 0;
  for (size_t i = 0; i < V; ++i)
    if (s.freeIndex[i] >= 0) s.freeIndex[i] = nFree++, s.vertexOfRow.push_back(uint32_t(i));

  std::vector<Eigen::Triplet<Real>> t;
  t.reserve(V + model.numPairs() * 8);
  if (dt > 0)
    for (size_t i = 0; i < V; ++i)
      if (s.freeIndex[i] >= 0) t.emplace_back(s.freeIndex[i], s.freeIndex[i], model.mass[i] / (dt * dt));
  // k_e G_e^T G_e = k_e (I - 11^T / n) on the element's vertices (G_e is a projection).
  for (size_t e = 0; e < model.numElements(); ++e) {
    const uint32_t b = model.elemStart[e], n = model.elemStart[e + 1] - b;
    const Real k = model.stiffness[e], off = -k / Real(n);
    for (uint32_t i = 0; i < n; ++i) {
      const int32_t ri = s.freeIndex[model.elemVerts[b + i]];
      if (ri < 0) continue;
      for (uint32_t j = 0; j < n; ++j) {
        const int32_t rj = s.freeIndex[model.elemVerts[b + j]];
        if (rj >= 0) t.emplace_back(ri, rj, i == j ? k + off : off);
      }
    }
  }
  // The volume constraints (projective.h): w_e B_e, B_e(i, k) = R0_i^T S^-1 R0_k, per coordinate.
  if (model.hasVolumeTerm()) {
    s.volumeWeight.assign(model.numElements(), 0), s.restInverse.resize(model.numElements());
    std::vector<Vec3> offsets;
    for (size_t e = 0; e < model.numElements(); ++e) {
      if (!(model.volumeStiffness[e] > 0)) continue;
      const uint32_t b = model.elemStart[e], n = model.elemStart[e + 1] - b;
      const Vec3* R0 = model.restOffsets(e, offsets);
      const Mat3 S = restSecondMoment(R0, n);
      const Mat3 Sinv = restMomentInverse(model.dim, S);
      const int D = model.dim == 2 ? 2 : 3;
      const Real w = Real(D * D) * model.volumeStiffness[e] / S.topLeftCorner(D, D).trace();
      s.volumeWeight[e] = w, s.restInverse[e] = Sinv;
      for (uint32_t i = 0; i < n; ++i) {
        const int32_t ri = s.freeIndex[model.elemVerts[b + i]];
        if (ri < 0) continue;
        for (uint32_t j = 0; j < n; ++j) {
          const int32_t rj = s.freeIndex[model.elemVerts[b + j]];
          if (rj >= 0) t.emplace_back(ri, rj, w * R0[i].dot(Sinv * R0[j]));
        }
      }
    }
  }
  SpMat& A = s.A;
  A.resize(nFree, nFree);
  A.setFromTriplets(t.begin(), t.end());
  s.diagonal.assign(V, 0.0);
  for (size_t i = 0; i < V; ++i)
    if (s.freeIndex[i] >= 0) s.diagonal[i] = A.coeff(s.freeIndex[i], s.freeIndex[i]);
  if (nFree > 0) {  // (METIS cannot order an empty graph)
    Eigen::SimplicialLDLT<SpMat, Eigen::Lower, FactorOrdering> ldlt(A);
    if (ldlt.info() != Eigen::Success)
      throw InputError(
          "implicit integrator: the global matrix could not be factored (a body without pins in a static solve?)");
    s.factor = SplitFactor::fromLdlt(ldlt);
  }
  s.rhs.resize(nFree, 3);
}

ProjectiveSolver::~ProjectiveSolver() = default;

Real ProjectiveSolver::dt() const { return impl_->dt; }

void ProjectiveSolver::step(std::vector<Vec3>& x, std::vector<Vec3>& v, std::vector<Quat>& q, const Vec3& gravity,
                            Real damping, int iterations, const std::vector<Vec3>& pinTargets, int rotationIterations,
                            const std::vector<uint32_t>& held, const std::vector<Vec3>& heldTargets,
                            const std::vector<Vec3>& heldNormals, std::vector<Vec3>* heldForces,
                            std::vector<PairConstraint>* pairs, const std::vector<Real>& heldFriction,
                            const std::vector<char>& heldLetGo, const std::vector<Vec3>& heldSlip) {
  Impl& s = *impl_;
  s.prepareHeld(held, heldTargets, heldNormals, heldFriction, heldLetGo, heldSlip);
  s.preparePairs(pairs);
  const RestModel& m = *s.model;
  const Real dt = s.dt, invDt2 = 1.0 / (dt * dt);
  const size_t V = m.numVertices();
  const std::vector<Vec3> x0 = x;
  // Inertial prediction y. The first iterate is x_n + dt v_n without the gravity term: with a
  // few passes the iteration stops short of the minimum in the direction it started from, and
  // starting at y would leave a resting body sagging by about (passes to converge / passes) dt^2 g
  // more than its equilibrium (a clamped bar 4x its static sag); this start has the equilibrium
  // as its fixed point. Rigid motion is still exact (one pass). Pinned vertices go to their targets.
  std::vector<Vec3> y(V);
  for (size_t i = 0; i < V; ++i) y[i] = freeFlight(x[i], v[i], dt, 1, gravity);
  for (size_t j = 0; j < s.pinned.size(); ++j) y[s.pinned[j]] = pinTargets.at(j);
  for (size_t i = 0; i < V; ++i) x[i] += dt * v[i];
  for (size_t j = 0; j < s.pinned.size(); ++j) x[s.pinned[j]] = pinTargets.at(j);
  for (int it = 0; it < std::max(iterations, 1); ++it) {
    for (size_t i = 0; i < V; ++i)
      if (s.freeIndex[i] >= 0) s.rhs.row(s.freeIndex[i]) = (m.mass[i] * invDt2 * y[i]).transpose();
    s.addElementTerms(x, q, rotationIterations);
    s.addPairTerms(x);
    s.solveInto(x);
    s.updatePairs(x);
    if (it + 1 < iterations) s.updateHolds();
  }
  // integration.h; per vertex when the regions set their own rates (model.h).
  for (size_t i = 0; i < V; ++i) v[i] = (x[i] - x0[i]) / dt * dampingFactor(m.vertexDamping(i, damping), dt);
  if (heldForces) {
    // The reaction of each hold still in place after the last pass: A x - b on its row.
    heldForces->assign(held.size(), Vec3::Zero());
    const Rhs Asol = s.appliedWithPairs();
    for (size_t k = 0; k < s.heldRows.size(); ++k) (*heldForces)[s.heldSource[k]] = s.heldReaction(s.heldRows[k], Asol);
  }
  s.heldRows.clear(), s.holds.clear();
  s.pairs = nullptr, s.activePairs.clear();
}

void ProjectiveSolver::applyInverse(const std::vector<Vec3>& r, std::vector<Vec3>& z) const {
  const Impl& s = *impl_;
  const std::vector<uint32_t>& vertexOf = s.vertexOfRow;
  z.assign(r.size(), Vec3::Zero());
  s.factorSolve([&](Eigen::Index row) { return r[vertexOf[size_t(row)]]; },
                [&](Eigen::Index row, const Vec3& v) { z[vertexOf[size_t(row)]] = v; });
}

void ProjectiveSolver::setTeam(ThreadTeam* team) { impl_->team = team; }

Real ProjectiveSolver::diagonal(uint32_t vertex) const { return impl_->diagonal.at(vertex); }

bool ProjectiveSolver::isFree(uint32_t vertex) const { return impl_->freeIndex.at(vertex) >= 0; }

int ProjectiveSolver::solveStatic(std::vector<Vec3>& x, std::vector<Quat>& q, const Vec3& gravity,
                                  const std::vector<Vec3>& pinTargets, int maxIterations, Real tolerance) {
  Impl& s = *impl_;
  const RestModel& m = *s.model;
  for (size_t j = 0; j < s.pinned.size(); ++j) x[s.pinned[j]] = pinTargets.at(j);
  std::vector<Vec3> before;
  s.heldRows.clear();
  for (int it = 1; it <= maxIterations; ++it) {
    for (size_t i = 0; i < m.numVertices(); ++i)
      if (s.freeIndex[i] >= 0) s.rhs.row(s.freeIndex[i]) = (m.mass[i] * gravity).transpose();
    s.addElementTerms(x, q, 20);
    before = x;
    s.solveInto(x);
    Real change = 0;
    for (size_t i = 0; i < x.size(); ++i) change = std::max(change, (x[i] - before[i]).norm());
    if (change < tolerance) return it;
  }
  return maxIterations;
}

}  // namespace gradel
