#include "gradel/element.h"

#include <cmath>

#include "gradel/rotation_fit.h"

namespace gradel {

Mat3 elementCovariance(const Vec3* x, const uint32_t* verts, const Vec3* R0, int n, Vec3* centroid) {
  Vec3 c = Vec3::Zero();
  for (int i = 0; i < n; ++i) c += x[verts[i]];
  c /= Real(n);
  // Because sum_i R0_i = 0, sum (x_i - c) R0_i^T = sum x_i R0_i^T: no need to subtract c here,
  // but doing so keeps the sum well-conditioned far from the origin.
  Mat3 A = Mat3::Zero();
  for (int i = 0; i < n; ++i) A.noalias() += (x[verts[i]] - c) * R0[i].transpose();
  if (centroid) *centroid = c;
  return A;
}

ElementResult elementForces(int dim, const Vec3* x, const uint32_t* verts, const Vec3* R0, int n,
                            Real k, Quat& q, Vec3* f, int maxIterations) {
  Vec3 c;
  const Mat3 A = elementCovariance(x, verts, R0, n, &c);
  if (dim == 2) {
    q = Quat(Eigen::AngleAxisd(fitRotation2(A), Vec3::UnitZ()));
  } else {
    fitRotation3(A, q, maxIterations, 1e-12);
  }
  const Mat3 M = q.toRotationMatrix();
  ElementResult res;
  Vec3 sum = Vec3::Zero();
  for (int i = 0; i < n; ++i) {
    const Vec3 d = M * R0[i] - (x[verts[i]] - c);
    f[i] = k * d;
    sum += f[i];
    res.sumSqDisp += d.squaredNorm();
  }
  // In exact arithmetic sum_i f_i = k (M sum R0_i - sum r_i) = 0. In floating point sum R0_i is
  // a constant rounding residue, which would push the body with a tiny constant force and make
  // linear momentum drift linearly in time. Removing the mean leaves only unbiased rounding.
  const Vec3 mean = sum / Real(n);
  for (int i = 0; i < n; ++i) f[i] -= mean;
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
