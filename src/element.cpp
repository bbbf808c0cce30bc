#include "gradel/element.h"

#include <cmath>

#include <Eigen/Eigenvalues>

#include "gradel/material.h"
#include "gradel/rotation_fit.h"

namespace gradel {

namespace {

// One pass over the element's vertices: centroid c, covariance A = sum (x_i - c) R0_i^T, and
// the rounding residue s = sum R0_i (zero in exact arithmetic).
struct Moments {
  Vec3 c;
  Mat3 A;
  Vec3 sumR0;
};

inline Moments moments(const Vec3* x, const uint32_t* verts, const Vec3* R0, int n) {
  Real sx = 0, sy = 0, sz = 0, s0 = 0, s1 = 0, s2 = 0;
  Real a00 = 0, a01 = 0, a02 = 0, a10 = 0, a11 = 0, a12 = 0, a20 = 0, a21 = 0, a22 = 0;
  for (int i = 0; i < n; ++i) {
    const Real* p = x[verts[i]].data();
    const Real* r = R0[i].data();
    const Real px = p[0], py = p[1], pz = p[2], rx = r[0], ry = r[1], rz = r[2];
    sx += px, sy += py, sz += pz;
    s0 += rx, s1 += ry, s2 += rz;
    a00 += px * rx, a01 += px * ry, a02 += px * rz;
    a10 += py * rx, a11 += py * ry, a12 += py * rz;
    a20 += pz * rx, a21 += pz * ry, a22 += pz * rz;
  }
  Moments m;
  m.c = Vec3(sx, sy, sz) / Real(n);
  m.sumR0 = Vec3(s0, s1, s2);
  // sum (x_i - c) R0_i^T = sum x_i R0_i^T - c (sum R0_i)^T.
  m.A << a00, a01, a02, a10, a11, a12, a20, a21, a22;
  m.A.noalias() -= m.c * m.sumR0.transpose();
  return m;
}

}  // namespace

Mat3 elementCovariance(const Vec3* x, const uint32_t* verts, const Vec3* R0, int n, Vec3* centroid) {
  const Moments m = moments(x, verts, R0, n);
  if (centroid) *centroid = m.c;
  return m.A;
}

// f_i = k (M R0_i - r_i), minus the mean force. In exact arithmetic sum_i f_i = k (M sum R0_i -
// sum r_i) = 0; in floating point sum R0_i is a constant rounding residue that would push the
// body with a tiny constant force and make linear momentum drift linearly in time. Its share
// M sum R0 / n is removed, leaving only unbiased rounding.
ElementResult elementForces(int dim, const Vec3* x, const uint32_t* verts, const Vec3* R0, int n, Real k, Quat& q,
                            Vec3* f, int maxIterations) {
  const Moments mo = moments(x, verts, R0, n);
  if (dim == 2) {
    q = Quat(Eigen::AngleAxisd(fitRotation2(mo.A), Vec3::UnitZ()));
  } else {
    fitRotation3(mo.A, q, maxIterations, 1e-12);
  }
  const Mat3 M = q.toRotationMatrix();
  const Vec3 e = mo.c - M * mo.sumR0 / Real(n);
  // Written out in scalars: d_i = M R0_i - x_i + e, f_i = k d_i.
  const Real m00 = M(0, 0), m01 = M(0, 1), m02 = M(0, 2), m10 = M(1, 0), m11 = M(1, 1), m12 = M(1, 2);
  const Real m20 = M(2, 0), m21 = M(2, 1), m22 = M(2, 2), e0 = e.x(), e1 = e.y(), e2 = e.z();
  ElementResult res;
  for (int i = 0; i < n; ++i) {
    const Real* r = R0[i].data();
    const Real* p = x[verts[i]].data();
    const Real d0 = m00 * r[0] + m01 * r[1] + m02 * r[2] - p[0] + e0;
    const Real d1 = m10 * r[0] + m11 * r[1] + m12 * r[2] - p[1] + e1;
    const Real d2 = m20 * r[0] + m21 * r[1] + m22 * r[2] - p[2] + e2;
    res.sumSqDisp += d0 * d0 + d1 * d1 + d2 * d2;
    f[i] = Vec3(k * d0, k * d1, k * d2);
  }
  res.energy = 0.5 * k * res.sumSqDisp;
  return res;
}

Mat3 restMomentInverse(int dim, const Mat3& S) {
  Mat3 inv = Mat3::Zero();
  if (dim == 2) {
    const Real det = S(0, 0) * S(1, 1) - S(0, 1) * S(1, 0);
    if (std::abs(det) > 1e-30 * (S(0, 0) * S(1, 1) + 1e-300)) {
      inv(0, 0) = S(1, 1) / det, inv(1, 1) = S(0, 0) / det;
      inv(0, 1) = -S(0, 1) / det, inv(1, 0) = -S(1, 0) / det;
      return inv;
    }
  } else if (const Real t = S.trace() / 3 + 1e-300; std::abs(S.determinant()) > 1e-30 * (t * t * t)) {
    return S.inverse();
  }
  Eigen::SelfAdjointEigenSolver<Mat3> es(S);
  const Real top = es.eigenvalues().cwiseAbs().maxCoeff();
  for (int k = 0; k < 3; ++k) {
    const Real l = es.eigenvalues()[k];
    if (std::abs(l) > 1e-12 * top) inv += es.eigenvectors().col(k) * es.eigenvectors().col(k).transpose() / l;
  }
  return inv;
}

Mat3 elementDeformationGradient(int dim, const Mat3& A, const Mat3& Sinv) {
  Mat3 F = A * Sinv;
  if (dim == 2) F.row(2).setZero(), F.col(2).setZero(), F(2, 2) = 1;
  return F;
}

Mat3 cofactor(const Mat3& F) {
  Mat3 C;
  C.row(0) = F.row(1).cross(F.row(2));
  C.row(1) = F.row(2).cross(F.row(0));
  C.row(2) = F.row(0).cross(F.row(1));
  return C;
}

Real restMomentTrace(const Vec3* R0, int n) {
  Real t = 0;
  for (int i = 0; i < n; ++i) t += R0[i].squaredNorm();
  return t;
}

Mat3 fitAffineRotation(int dim, const Mat3& F, const Quat& warm) {
  if (dim == 2) {
    const Real th = fitRotation2(F);
    Mat3 M = Mat3::Identity();
    M(0, 0) = std::cos(th), M(0, 1) = -std::sin(th), M(1, 0) = std::sin(th), M(1, 1) = std::cos(th);
    return M;
  }
  Quat q = warm;
  fitRotation3(F, q, 20, 1e-12);
  return q.toRotationMatrix();
}

bool volumeStrainMatrix(int dim, const Vec3* R0, int n, Mat3& V) {
  const Mat3 S = restSecondMoment(R0, size_t(n));
  const bool isotropic = S(0, 1) == 0 && S(1, 0) == 0 && S(0, 0) == S(1, 1) &&
                         (dim == 2 || (S(0, 2) == 0 && S(2, 0) == 0 && S(1, 2) == 0 && S(2, 1) == 0 && S(1, 1) == S(2, 2)));
  if (isotropic) return false;
  V = restMomentInverse(dim, S);
  return true;
}

Real elementVolumeForces(int dim, const Vec3* x, const uint32_t* verts, const Vec3* R0, int n, const Quat& q,
                         Real kappa, Vec3* f) {
  const Moments mo = moments(x, verts, R0, n);
  const Real D = dim == 2 ? 2 : 3;
  Mat3 V, H;
  Real ev;
  if (volumeStrainMatrix(dim, R0, n, V)) {
    const Mat3 F = mo.A * V;
    const Mat3 MF = fitAffineRotation(dim, F, q);
    ev = MF.cwiseProduct(F).sum() - D;  // tr(M_F^T F) - D
    H = -kappa * ev * (MF * V);
  } else {
    const Mat3 M = q.toRotationMatrix();
    const Real g = D / restMomentTrace(R0, n);
    ev = g * (M.cwiseProduct(mo.A).sum() - 1 / g * D);  // D (tr(M^T A) - tr S) / tr S
    H = -kappa * ev * g * M;
  }
  const Vec3 mean = mo.sumR0 / Real(n);  // rounding residue, removed so the forces sum to zero
  for (int i = 0; i < n; ++i) f[i] += H * (R0[i] - mean);
  return 0.5 * kappa * ev * ev;
}

Real elementDeterminant(int dim, const Vec3* x, const uint32_t* verts, const Vec3* R0, int n) {
  return deformationDeterminant(dim, elementCovariance(x, verts, R0, n), restSecondMoment(R0, size_t(n)));
}

Real deformationDeterminant(int dim, const Mat3& A, const Mat3& S) {
  if (dim == 2) return A.topLeftCorner<2, 2>().determinant() / S.topLeftCorner<2, 2>().determinant();
  return A.determinant() / S.determinant();
}

}  // namespace gradel
