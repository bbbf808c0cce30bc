#include "gradel/rotation_fit.h"

#include <Eigen/Cholesky>
#include <Eigen/SVD>
#include <cmath>

namespace gradel {

int fitRotation3(const Mat3& A, Quat& q, int maxIterations, Real tolerance) {
  // Maximise f(R) = tr(R^T A) over rotations, perturbing R in its own frame, R <- R exp([w]).
  // With B = R^T A:  f(w) ~ tr B + g.w - w^T H w / 2,  g = axial(B - B^T),  H = tr(B) I - sym(B).
  // Near the optimum H is positive definite and the Newton step w = H^-1 g converges
  // quadratically. Elsewhere (far from it, inverted or flat elements) we take the step of
  // Mueller et al. 2016, w = g / |tr B|, which never leaves the rotation group and climbs f.
  int it = 0;
  for (; it < maxIterations; ++it) {
    const Mat3 B = q.toRotationMatrix().transpose() * A;
    const Vec3 g(B(2, 1) - B(1, 2), B(0, 2) - B(2, 0), B(1, 0) - B(0, 1));
    const Real tr = B.trace();
    const Mat3 H = tr * Mat3::Identity() - 0.5 * (B + B.transpose());
    Vec3 w;
    Eigen::LLT<Mat3> llt(H);
    const Real scale = std::abs(tr) + 1e-300;
    if (llt.info() == Eigen::Success && H.diagonal().minCoeff() > 1e-6 * scale) {
      w = llt.solve(g);
    } else {
      w = g / (scale + 1e-9 * A.norm());
    }
    Real angle = w.norm();
    if (!(angle >= tolerance)) break;  // also stops on NaN
    if (angle > 1.0) w *= 1.0 / angle, angle = 1.0;  // a trust region: at most one radian a step
    q = q * Quat(Eigen::AngleAxisd(angle, w / angle));
    q.normalize();
  }
  return it;
}

Quat fitRotation3Cold(const Mat3& A) {
  Eigen::JacobiSVD<Mat3> svd(A, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Mat3 U = svd.matrixU();
  const Mat3 V = svd.matrixV();
  // Flip the column of the smallest singular value so that det(U V^T) = +1: the proper
  // rotation closest to A (maximises tr(R^T A) among rotations).
  if ((U * V.transpose()).determinant() < 0) U.col(2) *= -1;
  Quat q(U * V.transpose());
  q.normalize();
  fitRotation3(A, q, 20, 1e-13);
  return q;
}

Real fitRotation2(const Mat3& A) {
  const Real s = A(1, 0) - A(0, 1);
  const Real c = A(0, 0) + A(1, 1);
  if (s == 0 && c == 0) return 0;
  return std::atan2(s, c);
}

}  // namespace gradel
