#include "gradel/element.h"

#include <cmath>

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

Real elementDeterminant(int dim, const Vec3* x, const uint32_t* verts, const Vec3* R0, int n) {
  const Mat3 A = elementCovariance(x, verts, R0, n);
  Mat3 Q = Mat3::Zero();
  for (int i = 0; i < n; ++i) Q.noalias() += R0[i] * R0[i].transpose();
  if (dim == 2) return A.topLeftCorner<2, 2>().determinant() / Q.topLeftCorner<2, 2>().determinant();
  return A.determinant() / Q.determinant();
}

}  // namespace gradel
