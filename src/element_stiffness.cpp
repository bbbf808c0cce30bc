#include "gradel/element_stiffness.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

namespace gradel {

namespace {

Vec3 meanOf(const Vec3* R0, int n) {
  Vec3 s = Vec3::Zero();
  for (int i = 0; i < n; ++i) s += R0[i];
  return s / Real(n);
}

// T0 = tr(C) I - C, C = sum R0'_i R0'_i^T the rest covariance about the mean.
Mat3 restRotationMoment(const Vec3* R0, int n) {
  const Vec3 mean = meanOf(R0, n);
  Mat3 C = Mat3::Zero();
  for (int i = 0; i < n; ++i) {
    const Vec3 r = R0[i] - mean;
    C.noalias() += r * r.transpose();
  }
  return C.trace() * Mat3::Identity() - C;
}

}  // namespace

StiffnessFrame elementStiffnessFrame(int dim, const Mat3& A, const Quat& q, const Vec3* R0, int n) {
  StiffnessFrame fr;
  fr.M = q.toRotationMatrix();
  const Mat3 T0 = restRotationMoment(R0, n);
  const Mat3 MA = fr.M.transpose() * A;
  const Mat3 S = 0.5 * (MA + MA.transpose());
  const Mat3 T = S.trace() * Mat3::Identity() - S;
  if (dim == 2) {
    // Rotation about z only: T and T0 are their zz entries (S_xx + S_yy, C_xx + C_yy).
    const Real t0 = T0(2, 2);
    if (t0 > 0) fr.Tinv(2, 2) = 1 / std::max(T(2, 2), t0);
    return fr;
  }
  Eigen::SelfAdjointEigenSolver<Mat3> e0;
  e0.computeDirect(T0);
  const Vec3 l0 = e0.eigenvalues();
  if (!(l0.minCoeff() > 1e-12 * std::max(l0.maxCoeff(), Real(1e-300)))) return fr;  // flat element: no rotation term
  // W = T0^-1/2; the clamp runs on W T W (eigenvalues at least 1), T'^-1 = W V diag(1 / max(l, 1)) V^T W.
  const Mat3 W = e0.eigenvectors() * l0.cwiseSqrt().cwiseInverse().asDiagonal() * e0.eigenvectors().transpose();
  Eigen::SelfAdjointEigenSolver<Mat3> e;
  e.computeDirect(W * T * W);
  const Vec3 l = e.eigenvalues().cwiseMax(Real(1)).cwiseInverse();
  const Mat3 WV = W * e.eigenvectors();
  fr.Tinv = WV * l.asDiagonal() * WV.transpose();
  return fr;
}

StiffnessFrame elementRestStiffnessFrame(int dim, const Vec3* R0, int n) {
  StiffnessFrame fr;
  const Mat3 T0 = restRotationMoment(R0, n);
  if (dim == 2) {
    if (T0(2, 2) > 0) fr.Tinv(2, 2) = 1 / T0(2, 2);
    return fr;
  }
  // T0 >= 0 with eigenvalues l1 <= l2 <= l3: l1 = det / (l2 l3) >= det / tr^2, so det > 1e-12 tr^3
  // proves l1 > 1e-12 l3 (not flat) and the inverse is the adjugate over det; otherwise the
  // eigenvalues decide, as in elementStiffnessFrame.
  const Real tr = T0.trace(), det = T0.determinant();
  if (tr > 0 && det > 1e-12 * tr * tr * tr) {
    fr.Tinv = T0.inverse();
    return fr;
  }
  Eigen::SelfAdjointEigenSolver<Mat3> e0;
  e0.computeDirect(T0);
  const Vec3 l0 = e0.eigenvalues();
  if (!(l0.minCoeff() > 1e-12 * std::max(l0.maxCoeff(), Real(1e-300)))) return fr;  // flat element: no rotation term
  fr.Tinv = e0.eigenvectors() * l0.cwiseInverse().asDiagonal() * e0.eigenvectors().transpose();
  return fr;
}

void elementStiffnessProduct(const StiffnessFrame& fr, const Vec3* p, const uint32_t* verts, const Vec3* R0, int n,
                             Real k, Vec3* out) {
  const Vec3 mean = meanOf(R0, n);
  Vec3 pMean = Vec3::Zero();
  Mat3 dA = Mat3::Zero();
  for (int i = 0; i < n; ++i) {
    const Vec3& pi = p[verts[i]];
    pMean += pi;
    dA.noalias() += pi * (R0[i] - mean).transpose();
  }
  pMean /= Real(n);
  const Mat3 B = fr.M.transpose() * dA;
  const Vec3 b(B(2, 1) - B(1, 2), B(0, 2) - B(2, 0), B(1, 0) - B(0, 1));
  const Vec3 w = fr.Tinv * b;
  // M (w x R0'_i) = (M [w]x) R0'_i: one matrix for all vertices.
  Mat3 wx;
  wx << 0, -w.z(), w.y(), w.z(), 0, -w.x(), -w.y(), w.x(), 0;
  const Mat3 dM = fr.M * wx;
  const Vec3 dMmean = dM * mean;
  for (int i = 0; i < n; ++i) out[i] = k * (p[verts[i]] - pMean - dM * R0[i] + dMmean);
}

}  // namespace gradel
