#include "gradel/stability.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <utility>
#include <vector>

#include "gradel/element.h"
#include "gradel/element_stiffness.h"
#include "gradel/material.h"
#include "lcg.h"
#include "thread_team.h"

namespace gradel {

namespace {

// Each vertex's pairs in element order (a counting sort of the pairs by vertex, taken in order):
// vertex i's slots are [start[i], start[i + 1]), pair p sits in slot[p]. Both operators' vertex
// pass sums a vertex's slots in this order: the sums a serial scatter in element order makes.
struct PairsByVertex {
  std::vector<uint32_t> start, slot;
};

PairsByVertex pairsByVertex(const RestModel& m) {
  const size_t V = m.numVertices(), P = m.elemVerts.size();
  PairsByVertex out;
  out.start.assign(V + 1, 0);
  for (uint32_t v : m.elemVerts) ++out.start[v + 1];
  for (size_t i = 0; i < V; ++i) out.start[i + 1] += out.start[i];
  out.slot.resize(P);
  std::vector<uint32_t> fill(out.start.begin(), out.start.end() - 1);
  for (uint32_t p = 0; p < P; ++p) out.slot[p] = fill[m.elemVerts[p]]++;
  return out;
}

// M^-1/2 per vertex.
std::vector<Real> inverseSqrtMasses(const RestModel& m) {
  std::vector<Real> s(m.numVertices());
  for (size_t i = 0; i < s.size(); ++i) s[i] = 1 / std::sqrt(m.mass[i]);
  return s;
}

// y = M^-1/2 K M^-1/2 x over every element (frames at rest, fixed), z zeroed in 2D: with the rest
// rotation M = I (element_stiffness.h), per element e with centred offsets c_i = R0_i - mean R0,
//   b = sum_i c_i x p_i,  w = T0^-1 b,  (K p)_i = k ((p_i - mean p) - w x c_i),
// plus the volumetric term's rest Hessian kappa_e g g^T, g_i = (D / tr S_e) R0_i (element.h; an
// anisotropic S_e: g_i = V_e R0_i): (K p)_i += s_e g_i, s_e = kappa_e sum_j g_j . p_j.
// Two passes, as the step's element stage: each element its (mean p, w, s) alone, then each vertex
// the sum over its pairs in element order. Each result is computed by one member the same way, so
// the estimate is the same bits at any thread count.
struct RestOperator {
  /// What the vertex pass reads of an element: its mean p and w at the last product, and k.
  struct Term {
    Vec3 meanP, w;
    Real k;
  };
  const RestModel& m;
  ThreadTeam* team;  ///< The products' team (null: this thread); lanczos may switch it.
  std::vector<Vec3> restOffsets;  ///< R0 per pair (RestModel::pairRestOffsets), read in every product.
  std::vector<Mat3> tinv;    ///< T0^-1 per element (the frame at rest; 0 for a flat element).
  std::vector<Vec3> centre;  ///< mean R0 per element (0 to rounding).
  std::vector<Vec3> g;        ///< g_i per pair (empty without a volumetric term).
  std::vector<uint8_t> hasVolume;
  std::vector<Real> invSqrtMass;
  /// Each vertex's pairs in element order (slots): the element, c_i and g_i in slot order (the
  /// vertex pass reads them as one stream).
  std::vector<uint32_t> vertexPairStart, slotElement;
  std::vector<Vec3> slotCentred, slotG;
  mutable std::vector<Term> term;
  mutable std::vector<Real> volume;  ///< s_e at the last product.

  /// T0^-1 by elementRestStiffnessFrame (the general frame at the rest positions to rounding).
  RestOperator(const RestModel& model, ThreadTeam* t)
      : m(model), team(t), restOffsets(model.pairRestOffsets()), invSqrtMass(inverseSqrtMasses(model)) {
    const size_t E = m.numElements(), P = m.elemVerts.size();
    tinv.resize(E), centre.resize(E), term.resize(E);
    for (size_t e = 0; e < E; ++e) {
      const uint32_t b = m.elemStart[e], n = m.elemStart[e + 1] - b;
      tinv[e] = elementRestStiffnessFrame(m.dim, &restOffsets[b], int(n)).Tinv;
      Vec3 c = Vec3::Zero();
      for (uint32_t k = 0; k < n; ++k) c += restOffsets[b + k];
      centre[e] = c / Real(n);
      term[e].k = m.stiffness[e];
    }
    if (m.hasVolumeTerm()) {
      g.assign(P, Vec3::Zero()), hasVolume.assign(E, 0);
      for (size_t e = 0; e < E; ++e) {
        if (!(m.volumeStiffness[e] > 0)) continue;
        const uint32_t b = m.elemStart[e], n = m.elemStart[e + 1] - b;
        hasVolume[e] = 1;
        Mat3 Ve;
        if (volumeStrainMatrix(m.dim, &restOffsets[b], int(n), Ve))
          for (uint32_t k = 0; k < n; ++k) g[b + k] = Ve * restOffsets[b + k];
        else
          for (uint32_t k = 0; k < n; ++k)
            g[b + k] = (Real(m.dim == 2 ? 2 : 3) / restMomentTrace(&restOffsets[b], int(n))) * restOffsets[b + k];
      }
      volume.assign(E, 0), slotG.resize(P);
    }
    PairsByVertex byVertex = pairsByVertex(m);
    vertexPairStart = std::move(byVertex.start);
    slotElement.resize(P), slotCentred.resize(P);
    for (uint32_t e = 0; e < E; ++e)
      for (uint32_t p = m.elemStart[e]; p < m.elemStart[e + 1]; ++p) {
        const uint32_t slot = byVertex.slot[p];
        slotElement[slot] = e, slotCentred[slot] = restOffsets[p] - centre[e];
        if (!g.empty()) slotG[slot] = g[p];
      }
  }

  void apply(const std::vector<Vec3>& x, std::vector<Vec3>& y) const {
    forEachInChunks(team, m.numElements(), kElementChunk, [&](size_t e) {
      const uint32_t b = m.elemStart[e], n = m.elemStart[e + 1] - b;
      const Vec3 c0 = centre[e];
      Vec3 sum = Vec3::Zero(), bv = Vec3::Zero();
      for (uint32_t k = 0; k < n; ++k) {
        const uint32_t v = m.elemVerts[b + k];
        const Vec3 p = invSqrtMass[v] * x[v];
        sum += p;
        bv += (restOffsets[b + k] - c0).cross(p);
      }
      term[e].meanP = sum / Real(n);
      term[e].w = tinv[e] * bv;
      if (!g.empty() && hasVolume[e]) {
        Real s = 0;
        for (uint32_t k = 0; k < n; ++k) s += g[b + k].dot(invSqrtMass[m.elemVerts[b + k]] * x[m.elemVerts[b + k]]);
        volume[e] = m.volumeStiffness[e] * s;
      }
    });
    forEachInChunks(team, m.numVertices(), kVertexChunk, [&](size_t i) {
      const Vec3 p = invSqrtMass[i] * x[i];
      Vec3 s = Vec3::Zero();
      for (uint32_t k = vertexPairStart[i]; k < vertexPairStart[i + 1]; ++k) {
        const uint32_t e = slotElement[k];
        const Term& t = term[e];
        s += t.k * (p - t.meanP - t.w.cross(slotCentred[k]));
        if (!g.empty() && hasVolume[e]) s += volume[e] * slotG[k];
      }
      s *= invSqrtMass[i];
      if (m.dim == 2) s.z() = 0;
      y[i] = s;
    });
  }

  static constexpr size_t kVertexChunk = 2048, kElementChunk = 256;
};

// The estimate from scratch's operator, the bits every dt = auto of a new World depends on: per
// element the product of element_stiffness.h with the general frame at the rest positions, each
// element into its own pairs' slots, then each vertex the sum of its slots in element order (the
// sum a serial scatter in element order makes, bit for bit, at any thread count). The same operator
// as RestOperator to rounding (48 Lanczos products amplify the difference: dt 6 ppm apart), ~1.5x
// its cost per product. Kept for its bits: every scene's dt = auto stays what it was (at
// RestOperator's dt one body-contact test, two 8-voxel balls head on at 0.5 m/s, ended a step with
// a vertex 9.6 um inside the other ball: a weakness of the folded-surface allowance, since fixed,
// body_contact_response.cpp allowedDepth).
struct ReferenceOperator {
  const RestModel& m;
  ThreadTeam* team;
  std::vector<Vec3> restOffsets;  ///< R0 per pair (RestModel::pairRestOffsets), read in every product.
  std::vector<StiffnessFrame> frames;
  std::vector<Real> restScale;  ///< D / tr S_e per element (empty without a volumetric term).
  /// Per element: whether S_e is anisotropic, and then V_e (g_i = V_e R0_i, element.h).
  std::vector<std::pair<bool, Mat3>> restStrain;
  std::vector<Real> invSqrtMass;
  std::vector<uint32_t> vertexPairStart, vertexPairs;  ///< Each vertex's pairs, in element order.
  std::vector<uint8_t> pairVolume;                     ///< Whether the pair's element adds a volumetric part.
  mutable std::vector<Vec3> scaled, pairOut, pairVolumeOut;

  ReferenceOperator(const RestModel& model, ThreadTeam* t)
      : m(model), team(t), restOffsets(model.pairRestOffsets()), invSqrtMass(inverseSqrtMasses(model)) {
    const size_t E = m.numElements(), V = m.numVertices(), P = m.elemVerts.size();
    frames.resize(E);
    for (size_t e = 0; e < E; ++e) {
      const uint32_t b = m.elemStart[e], n = m.elemStart[e + 1] - b;
      const Mat3 A = elementCovariance(m.restPositions.data(), &m.elemVerts[b], &restOffsets[b], int(n));
      frames[e] = elementStiffnessFrame(m.dim, A, Quat::Identity(), &restOffsets[b], int(n));
    }
    if (m.hasVolumeTerm()) {
      restScale.resize(E), restStrain.resize(E);
      pairVolume.assign(P, 0);
      for (size_t e = 0; e < E; ++e) {
        const uint32_t b = m.elemStart[e], n = m.elemStart[e + 1] - b;
        restScale[e] = Real(m.dim == 2 ? 2 : 3) / restMomentTrace(&restOffsets[b], int(n));
        if (volumeStrainMatrix(m.dim, &restOffsets[b], int(n), restStrain[e].second)) restStrain[e].first = true;
        if (m.volumeStiffness[e] > 0) std::fill(pairVolume.begin() + b, pairVolume.begin() + b + n, uint8_t(1));
      }
      pairVolumeOut.resize(P);
    }
    PairsByVertex byVertex = pairsByVertex(m);
    vertexPairStart = std::move(byVertex.start);
    vertexPairs.resize(P);
    for (uint32_t p = 0; p < P; ++p) vertexPairs[byVertex.slot[p]] = p;
    scaled.resize(V), pairOut.resize(P);
  }

  void apply(const std::vector<Vec3>& x, std::vector<Vec3>& y) const {
    forEachInChunks(team, m.numVertices(), kVertexChunk, [&](size_t i) { scaled[i] = invSqrtMass[i] * x[i]; });
    forEachInChunks(team, m.numElements(), kElementChunk, [&](size_t e) {
      const uint32_t b = m.elemStart[e], n = m.elemStart[e + 1] - b;
      elementStiffnessProduct(frames[e], scaled.data(), &m.elemVerts[b], &restOffsets[b], int(n), m.stiffness[e],
                              &pairOut[b]);
      if (!restScale.empty() && m.volumeStiffness[e] > 0 && restStrain[e].first) {
        const Mat3& Ve = restStrain[e].second;
        Real s = 0;
        for (uint32_t k = 0; k < n; ++k) s += (Ve * restOffsets[b + k]).dot(scaled[m.elemVerts[b + k]]);
        s *= m.volumeStiffness[e];
        for (uint32_t k = 0; k < n; ++k) pairVolumeOut[b + k] = s * (Ve * restOffsets[b + k]);
      } else if (!restScale.empty() && m.volumeStiffness[e] > 0) {
        Real s = 0;
        for (uint32_t k = 0; k < n; ++k) s += restOffsets[b + k].dot(scaled[m.elemVerts[b + k]]);
        s *= m.volumeStiffness[e] * restScale[e] * restScale[e];
        for (uint32_t k = 0; k < n; ++k) pairVolumeOut[b + k] = s * restOffsets[b + k];
      }
    });
    const bool volume = !pairVolume.empty();
    forEachInChunks(team, m.numVertices(), kVertexChunk, [&](size_t i) {
      Vec3 s = Vec3::Zero();
      for (uint32_t k = vertexPairStart[i]; k < vertexPairStart[i + 1]; ++k) {
        const uint32_t p = vertexPairs[k];
        s += pairOut[p];
        if (volume && pairVolume[p]) s += pairVolumeOut[p];
      }
      s *= invSqrtMass[i];
      if (m.dim == 2) s.z() = 0;
      y[i] = s;
    });
  }

  static constexpr size_t kVertexChunk = 2048, kElementChunk = 256;
};

/// The team carries on only when its iteration took less than this share of the serial one.
constexpr double kTeamMargin = 0.9;

double dot(const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
  double s = 0;
  for (size_t i = 0; i < a.size(); ++i) s += a[i].dot(b[i]);
  return s;
}

// Lanczos from the unit vector q (`iterations` products at most): the estimate, and when
// `ritzVector` is given the Ritz vector of the largest Ritz value (the Lanczos vectors kept in
// single precision meanwhile: it only starts the next estimate, stabilityWarmStart).
template <class Operator>
FrequencyEstimate lanczos(const RestModel& m, std::vector<Vec3> q, int iterations, std::vector<Vec3>* ritzVector,
                          ThreadTeam* team) {
  FrequencyEstimate est;
  const size_t V = m.numVertices();
  // The upper bound: every element's K_e <= k_e I (with a volumetric term, + kappa_e sum |g_i|^2:
  // RestModel::elementStiffnessBound), so K <= diag(sum of the bounds at each vertex).
  std::vector<Real> kSum(V, 0.0);
  for (size_t e = 0; e < m.numElements(); ++e) {
    const Real k = m.elementStiffnessBound(e);
    for (uint32_t p = m.elemStart[e]; p < m.elemStart[e + 1]; ++p) kSum[m.elemVerts[p]] += k;
  }
  double bound = 0;
  for (size_t i = 0; i < V; ++i) bound = std::max(bound, double(kSum[i] / m.mass[i]));
  est.gershgorin = std::sqrt(bound);

  Operator op(m, team);
  // Element-wise vector work on the team (each entry alone: the same bits); the dot products
  // stay serial (their order of summation is the estimate's bits). Whether the team pays is
  // measured, as the step's governor does (thread_team.h): the first iteration runs on this
  // thread, the second on the team, and the faster carries on (on a machine with other busy
  // programs each of the ~4 hand-overs per iteration can wait a time slice for a member).
  ThreadTeam* const offered = team && team->members() > 1 ? team : nullptr;
  op.team = nullptr;
  auto each = [&](auto&& f) { forEachInChunks(op.team, V, Operator::kVertexChunk, f); };
  double serialSeconds = 0;
  std::vector<Vec3> qPrev(V, Vec3::Zero()), w(V);
  std::vector<std::vector<Eigen::Vector3f>> kept;
  std::vector<double> alpha, beta;
  double betaPrev = 0;
  if (ritzVector) {
    kept.reserve(size_t(iterations));
    kept.emplace_back(V);
    each([&](size_t i) { kept.back()[i] = q[i].cast<float>(); });
  }
  for (int j = 0; j < iterations; ++j) {
    const auto t0 = std::chrono::steady_clock::now();
    if (j == 1 && offered) op.team = offered;
    op.apply(q, w);
    const double a = dot(q, w);
    each([&](size_t i) { w[i] -= a * q[i] + betaPrev * qPrev[i]; });
    const double b = std::sqrt(dot(w, w));
    alpha.push_back(a), beta.push_back(b);
    est.iterations = j + 1;
    if (!(b > 1e-12 * std::max(std::abs(a), 1e-300))) break;  // the Krylov space closed: theta is exact
    qPrev.swap(q);
    // The next Lanczos vector, and its single-precision copy for the Ritz vector (kept[j + 1]).
    std::vector<Eigen::Vector3f>* to = nullptr;
    if (ritzVector && j + 1 < iterations) to = &kept.emplace_back(V);
    each([&](size_t i) {
      q[i] = w[i] / b;
      if (to) (*to)[i] = q[i].cast<float>();
    });
    betaPrev = b;
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (j == 0) serialSeconds = seconds;
    if (j == 1 && op.team && !(seconds < kTeamMargin * serialSeconds)) op.team = nullptr;
  }
  const int k = int(alpha.size());
  Eigen::MatrixXd T = Eigen::MatrixXd::Zero(k, k);
  for (int i = 0; i < k; ++i) {
    T(i, i) = alpha[i];
    if (i + 1 < k) T(i, i + 1) = T(i + 1, i) = beta[i];
  }
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(T);
  const double theta = std::max(0.0, eig.eigenvalues()(k - 1));
  const double residual = std::abs(beta[k - 1] * eig.eigenvectors()(k - 1, k - 1));
  est.ritz = std::sqrt(theta);
  est.omega = std::sqrt(std::min(theta + residual, bound));
  if (ritzVector) {
    ritzVector->assign(V, Vec3::Zero());
    const Eigen::VectorXd c = eig.eigenvectors().col(k - 1);
    each([&](size_t i) {
      Vec3 r = Vec3::Zero();
      for (int j = 0; j < k; ++j) r += c(j) * kept[size_t(j)][i].cast<double>();
      (*ritzVector)[i] = r;
    });
  }
  return est;
}

}  // namespace

FrequencyEstimate highestFrequency(const RestModel& m, int iterations, std::vector<Vec3>* ritzVector, ThreadTeam* team) {
  const size_t V = m.numVertices();
  if (m.numElements() == 0 || V == 0) return {};
  // A fixed start (a 64-bit LCG): the same estimate on every run and thread count.
  std::vector<Vec3> q(V);
  Lcg r{0x9E3779B97F4A7C15ull};
  for (Vec3& v : q) v = Vec3(r.centred(), r.centred(), m.dim == 2 ? 0.0 : r.centred());
  const double n0 = std::sqrt(dot(q, q));
  for (Vec3& v : q) v /= n0;
  return lanczos<ReferenceOperator>(m, std::move(q), iterations, ritzVector, team);
}

FrequencyEstimate highestFrequencyFrom(const RestModel& m, std::vector<Vec3> start, int iterations,
                                       std::vector<Vec3>* ritzVector, ThreadTeam* team) {
  const size_t V = m.numVertices();
  if (m.numElements() == 0 || V == 0) return {};
  if (start.size() != V) throw std::invalid_argument("highestFrequencyFrom: the start's size is not the model's");
  if (m.dim == 2)
    for (Vec3& v : start) v.z() = 0;
  const double n0 = std::sqrt(dot(start, start));
  if (!(n0 > 0) || !std::isfinite(n0)) return highestFrequency(m, iterations, ritzVector, team);
  for (Vec3& v : start) v /= n0;
  return lanczos<RestOperator>(m, std::move(start), iterations, ritzVector, team);
}

}  // namespace gradel
