#include "gradel/stability.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <utility>
#include <vector>

#include "gradel/element.h"
#include "gradel/element_stiffness.h"
#include "gradel/material.h"
#include "lcg.h"

namespace gradel {

namespace {

// y = M^-1/2 K M^-1/2 x over every element (frames at rest, fixed), z zeroed in 2D. K includes
// the volumetric term's rest Hessian kappa_e g g^T, g_i = (D / tr S_e) R0_i (element.h, M = I;
// an anisotropic S_e: g_i = V_e R0_i).
struct RestOperator {
  const RestModel& m;
  std::vector<StiffnessFrame> frames;
  std::vector<Real> restScale;  ///< D / tr S_e per element (empty without a volumetric term).
  /// Per element: whether S_e is anisotropic, and then V_e (g_i = V_e R0_i, element.h).
  std::vector<std::pair<bool, Mat3>> restStrain;
  std::vector<Real> invSqrtMass;
  mutable std::vector<Vec3> scaled, elementOut;

  /// restFrames: the frames by elementRestStiffnessFrame (the same to rounding, cheaper; the warm
  /// start's estimate) instead of the general frame at the rest positions (the estimate's bits
  /// from scratch, which every dt = auto depends on).
  RestOperator(const RestModel& model, bool restFrames) : m(model) {
    const size_t E = m.numElements(), V = m.numVertices();
    frames.resize(E);
    size_t largest = 0;
    for (size_t e = 0; e < E; ++e) {
      const uint32_t b = m.elemStart[e], n = m.elemStart[e + 1] - b;
      if (restFrames) {
        frames[e] = elementRestStiffnessFrame(m.dim, &m.restOffsets[b], int(n));
      } else {
        const Mat3 A = elementCovariance(m.restPositions.data(), &m.elemVerts[b], &m.restOffsets[b], int(n));
        frames[e] = elementStiffnessFrame(m.dim, A, Quat::Identity(), &m.restOffsets[b], int(n));
      }
      largest = std::max<size_t>(largest, n);
    }
    if (m.hasVolumeTerm()) {
      restScale.resize(E), restStrain.resize(E);
      for (size_t e = 0; e < E; ++e) {
        const uint32_t b = m.elemStart[e], n = m.elemStart[e + 1] - b;
        restScale[e] = Real(m.dim == 2 ? 2 : 3) / restMomentTrace(&m.restOffsets[b], int(n));
        if (volumeStrainMatrix(m.dim, &m.restOffsets[b], int(n), restStrain[e].second)) restStrain[e].first = true;
      }
    }
    invSqrtMass.resize(V);
    for (size_t i = 0; i < V; ++i) invSqrtMass[i] = 1 / std::sqrt(m.mass[i]);
    scaled.resize(V), elementOut.resize(largest);
  }

  void apply(const std::vector<Vec3>& x, std::vector<Vec3>& y) const {
    const size_t V = m.numVertices();
    for (size_t i = 0; i < V; ++i) scaled[i] = invSqrtMass[i] * x[i];
    std::fill(y.begin(), y.end(), Vec3::Zero());
    for (size_t e = 0; e < m.numElements(); ++e) {
      const uint32_t b = m.elemStart[e], n = m.elemStart[e + 1] - b;
      elementStiffnessProduct(frames[e], scaled.data(), &m.elemVerts[b], &m.restOffsets[b], int(n), m.stiffness[e],
                              elementOut.data());
      for (uint32_t k = 0; k < n; ++k) y[m.elemVerts[b + k]] += elementOut[k];
      if (!restScale.empty() && m.volumeStiffness[e] > 0 && restStrain[e].first) {
        const Mat3& Ve = restStrain[e].second;
        Real s = 0;
        for (uint32_t k = 0; k < n; ++k) s += (Ve * m.restOffsets[b + k]).dot(scaled[m.elemVerts[b + k]]);
        s *= m.volumeStiffness[e];
        for (uint32_t k = 0; k < n; ++k) y[m.elemVerts[b + k]] += s * (Ve * m.restOffsets[b + k]);
      } else if (!restScale.empty() && m.volumeStiffness[e] > 0) {
        Real s = 0;
        for (uint32_t k = 0; k < n; ++k) s += m.restOffsets[b + k].dot(scaled[m.elemVerts[b + k]]);
        s *= m.volumeStiffness[e] * restScale[e] * restScale[e];
        for (uint32_t k = 0; k < n; ++k) y[m.elemVerts[b + k]] += s * m.restOffsets[b + k];
      }
    }
    for (size_t i = 0; i < V; ++i) {
      y[i] *= invSqrtMass[i];
      if (m.dim == 2) y[i].z() = 0;
    }
  }
};

double dot(const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
  double s = 0;
  for (size_t i = 0; i < a.size(); ++i) s += a[i].dot(b[i]);
  return s;
}

// Lanczos from the unit vector q (`iterations` products at most): the estimate, and when
// `ritzVector` is given the Ritz vector of the largest Ritz value (the Lanczos vectors kept in
// single precision meanwhile: it only starts the next estimate, stabilityWarmStart).
FrequencyEstimate lanczos(const RestModel& m, std::vector<Vec3> q, int iterations, std::vector<Vec3>* ritzVector,
                          bool restFrames) {
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

  const RestOperator op(m, restFrames);
  std::vector<Vec3> qPrev(V, Vec3::Zero()), w(V);
  std::vector<std::vector<Eigen::Vector3f>> kept;
  std::vector<double> alpha, beta;
  double betaPrev = 0;
  for (int j = 0; j < iterations; ++j) {
    if (ritzVector) {
      kept.emplace_back(V);
      for (size_t i = 0; i < V; ++i) kept.back()[i] = q[i].cast<float>();
    }
    op.apply(q, w);
    const double a = dot(q, w);
    for (size_t i = 0; i < V; ++i) w[i] -= a * q[i] + betaPrev * qPrev[i];
    const double b = std::sqrt(dot(w, w));
    alpha.push_back(a), beta.push_back(b);
    est.iterations = j + 1;
    if (!(b > 1e-12 * std::max(std::abs(a), 1e-300))) break;  // the Krylov space closed: theta is exact
    qPrev.swap(q);
    for (size_t i = 0; i < V; ++i) q[i] = w[i] / b;
    betaPrev = b;
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
    for (int j = 0; j < k; ++j) {
      const double c = eig.eigenvectors()(j, k - 1);
      for (size_t i = 0; i < V; ++i) (*ritzVector)[i] += c * kept[j][i].cast<double>();
    }
  }
  return est;
}

}  // namespace

FrequencyEstimate highestFrequency(const RestModel& m, int iterations, std::vector<Vec3>* ritzVector) {
  const size_t V = m.numVertices();
  if (m.numElements() == 0 || V == 0) return {};
  // A fixed start (a 64-bit LCG): the same estimate on every run and thread count.
  std::vector<Vec3> q(V);
  Lcg r{0x9E3779B97F4A7C15ull};
  for (Vec3& v : q) v = Vec3(r.centred(), r.centred(), m.dim == 2 ? 0.0 : r.centred());
  const double n0 = std::sqrt(dot(q, q));
  for (Vec3& v : q) v /= n0;
  return lanczos(m, std::move(q), iterations, ritzVector, false);
}

FrequencyEstimate highestFrequencyFrom(const RestModel& m, std::vector<Vec3> start, int iterations,
                                       std::vector<Vec3>* ritzVector) {
  const size_t V = m.numVertices();
  if (m.numElements() == 0 || V == 0) return {};
  if (start.size() != V) throw std::invalid_argument("highestFrequencyFrom: the start's size is not the model's");
  if (m.dim == 2)
    for (Vec3& v : start) v.z() = 0;
  const double n0 = std::sqrt(dot(start, start));
  if (!(n0 > 0) || !std::isfinite(n0)) return highestFrequency(m, iterations, ritzVector);
  for (Vec3& v : start) v /= n0;
  return lanczos(m, std::move(start), iterations, ritzVector, true);
}

}  // namespace gradel
