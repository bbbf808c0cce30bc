#include "gradel/rotation_fit.h"

#include <Eigen/SVD>
#include <cmath>

#include "simd.h"

namespace gradel {

int fitRotation3(const Mat3& A, Quat& q, int maxIterations, Real tolerance) {
  // Maximise f(R) = tr(R^T A) over rotations, perturbing R in its own frame, R <- R exp([w]).
  // With B = R^T A:  f(w) ~ tr B + g.w - w^T H w / 2,  g = axial(B - B^T),  H = tr(B) I - sym(B).
  // Near the optimum H is positive definite and the Newton step w = H^-1 g converges
  // quadratically. Elsewhere (far from it, inverted or flat elements) we take the step of
  // Mueller et al. 2016, w = g / |tr B|, which never leaves the rotation group and climbs f.
  // Written out in scalars: this runs once per element per step (the hot loop).
  Real qw = q.w(), qx = q.x(), qy = q.y(), qz = q.z();
  const Real scaleA = std::abs(A(0, 0)) + std::abs(A(1, 1)) + std::abs(A(2, 2)) + std::abs(A(0, 1)) +
                      std::abs(A(1, 0)) + std::abs(A(0, 2)) + std::abs(A(2, 0)) + std::abs(A(1, 2)) + std::abs(A(2, 1));
  int it = 0;
  for (; it < maxIterations; ++it) {
    // R from the unit quaternion.
    const Real xx = qx * qx, yy = qy * qy, zz = qz * qz, xy = qx * qy, xz = qx * qz, yz = qy * qz;
    const Real wx = qw * qx, wy = qw * qy, wz = qw * qz;
    const Real R00 = 1 - 2 * (yy + zz), R01 = 2 * (xy - wz), R02 = 2 * (xz + wy);
    const Real R10 = 2 * (xy + wz), R11 = 1 - 2 * (xx + zz), R12 = 2 * (yz - wx);
    const Real R20 = 2 * (xz - wy), R21 = 2 * (yz + wx), R22 = 1 - 2 * (xx + yy);
    // B = R^T A.
    Real B[3][3];
    for (int c = 0; c < 3; ++c) {
      B[0][c] = R00 * A(0, c) + R10 * A(1, c) + R20 * A(2, c);
      B[1][c] = R01 * A(0, c) + R11 * A(1, c) + R21 * A(2, c);
      B[2][c] = R02 * A(0, c) + R12 * A(1, c) + R22 * A(2, c);
    }
    const Real g0 = B[2][1] - B[1][2], g1 = B[0][2] - B[2][0], g2 = B[1][0] - B[0][1];
    const Real tr = B[0][0] + B[1][1] + B[2][2];
    // H = tr I - sym(B), symmetric.
    const Real h00 = tr - B[0][0], h11 = tr - B[1][1], h22 = tr - B[2][2];
    const Real h01 = -0.5 * (B[0][1] + B[1][0]), h02 = -0.5 * (B[0][2] + B[2][0]), h12 = -0.5 * (B[1][2] + B[2][1]);
    // Positive definite by Sylvester's criterion -> Newton via the adjugate; else Mueller's step.
    const Real c00 = h11 * h22 - h12 * h12, c01 = h02 * h12 - h01 * h22, c02 = h01 * h12 - h02 * h11;
    const Real det = h00 * c00 + h01 * c01 + h02 * c02;
    const Real m2 = h00 * h11 - h01 * h01;
    const Real scale = std::abs(tr) + 1e-300;
    Real w0, w1, w2;
    const bool newton = h00 > 1e-6 * scale && m2 > 1e-12 * scale * scale && det > 1e-18 * scale * scale * scale;
    if (newton) {
      const Real c11 = h00 * h22 - h02 * h02, c12 = h01 * h02 - h00 * h12, c22 = m2;
      const Real inv = 1 / det;
      w0 = (c00 * g0 + c01 * g1 + c02 * g2) * inv;
      w1 = (c01 * g0 + c11 * g1 + c12 * g2) * inv;
      w2 = (c02 * g0 + c12 * g1 + c22 * g2) * inv;
    } else {
      const Real inv = 1 / (scale + 1e-9 * scaleA);
      w0 = g0 * inv, w1 = g1 * inv, w2 = g2 * inv;
    }
    Real angle2 = w0 * w0 + w1 * w1 + w2 * w2;
    if (!(angle2 >= tolerance * tolerance)) break;  // converged (also stops on NaN)
    if (angle2 > 1.0) {                             // a trust region: at most one radian a step
      const Real s = 1 / std::sqrt(angle2);
      w0 *= s, w1 *= s, w2 *= s, angle2 = 1;
    }
    // q <- q * exp(w / 2): exact half-angle rotation, with sin and cos from their series for
    // small angles (the usual case with a warm start) to stay cheap.
    const Real angle = std::sqrt(angle2);
    Real cw, sw;  // cos(angle / 2), sin(angle / 2) / angle
    if (angle < 1e-3) {
      cw = 1 - angle2 / 8;
      sw = 0.5 - angle2 / 48;
    } else {
      cw = std::cos(0.5 * angle);
      sw = std::sin(0.5 * angle) / angle;
    }
    const Real dx = sw * w0, dy = sw * w1, dz = sw * w2;
    const Real nw = qw * cw - qx * dx - qy * dy - qz * dz;
    const Real nx = qw * dx + qx * cw + qy * dz - qz * dy;
    const Real ny = qw * dy - qx * dz + qy * cw + qz * dx;
    const Real nz = qw * dz + qx * dy - qy * dx + qz * cw;
    const Real norm = 1 / std::sqrt(nw * nw + nx * nx + ny * ny + nz * nz);
    qw = nw * norm, qx = nx * norm, qy = ny * norm, qz = nz * norm;
    // Newton converges quadratically: after a step this small the next one would be below
    // the tolerance, so skip the iteration that would only confirm it.
    if (newton && angle2 < tolerance) {
      ++it;
      break;
    }
  }
  q = Quat(qw, qx, qy, qz);
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

// ---- four fits at once ----------------------------------------------------------------------
// One lane per element (simd.h).
void fitRotation3Batch(RotationBatch& b, int maxIterations, Real tolerance) {
  using namespace simd;
  d4 qw = load4(b.q[0]), qx = load4(b.q[1]), qy = load4(b.q[2]), qz = load4(b.q[3]);
  d4 A[9];
  for (int k = 0; k < 9; ++k) A[k] = load4(b.A[k]);
  const d4 tol = splat(tolerance), tol2 = splat(tolerance * tolerance);
  m4 active = (m4)splat(0) == (m4)splat(0);  // all ones
  for (int it = 0; it < maxIterations; ++it) {
    const d4 xx = qx * qx, yy = qy * qy, zz = qz * qz, xy = qx * qy, xz = qx * qz, yz = qy * qz;
    const d4 wx = qw * qx, wy = qw * qy, wz = qw * qz;
    const d4 R00 = 1 - 2 * (yy + zz), R01 = 2 * (xy - wz), R02 = 2 * (xz + wy);
    const d4 R10 = 2 * (xy + wz), R11 = 1 - 2 * (xx + zz), R12 = 2 * (yz - wx);
    const d4 R20 = 2 * (xz - wy), R21 = 2 * (yz + wx), R22 = 1 - 2 * (xx + yy);
    d4 B[3][3];
    for (int c = 0; c < 3; ++c) {
      B[0][c] = R00 * A[c] + R10 * A[3 + c] + R20 * A[6 + c];
      B[1][c] = R01 * A[c] + R11 * A[3 + c] + R21 * A[6 + c];
      B[2][c] = R02 * A[c] + R12 * A[3 + c] + R22 * A[6 + c];
    }
    const d4 g0 = B[2][1] - B[1][2], g1 = B[0][2] - B[2][0], g2 = B[1][0] - B[0][1];
    const d4 tr = B[0][0] + B[1][1] + B[2][2];
    const d4 h00 = tr - B[0][0], h11 = tr - B[1][1], h22 = tr - B[2][2];
    const d4 h01 = -0.5 * (B[0][1] + B[1][0]), h02 = -0.5 * (B[0][2] + B[2][0]), h12 = -0.5 * (B[1][2] + B[2][1]);
    const d4 c00 = h11 * h22 - h12 * h12, c01 = h02 * h12 - h01 * h22, c02 = h01 * h12 - h02 * h11;
    const d4 det = h00 * c00 + h01 * c01 + h02 * c02;
    const d4 m2 = h00 * h11 - h01 * h01;
    const d4 scale = abs(tr) + 1e-300;
    const m4 newton = (h00 > 1e-6 * scale) & (m2 > 1e-12 * scale * scale) & (det > 1e-18 * scale * scale * scale);
    const d4 c11 = h00 * h22 - h02 * h02, c12 = h01 * h02 - h00 * h12, c22 = m2;
    const d4 invDet = 1 / select(newton, det, splat(1));
    d4 w0 = (c00 * g0 + c01 * g1 + c02 * g2) * invDet;
    d4 w1 = (c01 * g0 + c11 * g1 + c12 * g2) * invDet;
    d4 w2 = (c02 * g0 + c12 * g1 + c22 * g2) * invDet;
    if (!none(~newton)) {  // Mueller's step in some lane (rare with a warm start): off the usual path
      d4 scaleA = splat(0);
      for (int k = 0; k < 9; ++k) scaleA += abs(A[k]);
      const d4 invMueller = 1 / (scale + 1e-9 * scaleA);
      w0 = select(newton, w0, g0 * invMueller);
      w1 = select(newton, w1, g1 * invMueller);
      w2 = select(newton, w2, g2 * invMueller);
    }
    d4 angle2 = w0 * w0 + w1 * w1 + w2 * w2;
    active &= angle2 >= tol2;  // converged (or NaN): this lane stops unchanged
    if (none(active)) break;
    const m4 big = angle2 > 1.0;  // trust region: at most one radian a step
    if (!none(big)) {  // (rare with a warm start: the root and division off the usual chain)
      const d4 s = select(big, 1 / sqrt(select(big, angle2, splat(1))), splat(1));
      w0 *= s, w1 *= s, w2 *= s;
      angle2 = select(big, splat(1), angle2);
    }
    // q <- q * exp(w / 2): cos(h) and sin(h) / (2 h), h = angle / 2 <= 1/2, from their series
    // to h^14 (the next terms are below 1e-18); when every active lane turns by less than 0.01 rad
    // (the usual case with a warm start: a short dependency chain), to h^6 (h^8 / 8! < 1e-23).
    const d4 u = 0.25 * angle2;  // h^2
    d4 cw, sw;
    if (none(active & (angle2 >= 1e-4))) {
      cw = 1 + u * (-1.0 / 2 + u * (1.0 / 24 + u * (-1.0 / 720)));
      sw = 0.5 * (1 + u * (-1.0 / 6 + u * (1.0 / 120 + u * (-1.0 / 5040))));
    } else {
      cw = 1 + u * (-1.0 / 2 +
                    u * (1.0 / 24 +
                         u * (-1.0 / 720 + u * (1.0 / 40320 + u * (-1.0 / 3628800 +
                                                                   u * (1.0 / 479001600 + u * (-1.0 / 87178291200.0)))))));
      sw = 0.5 * (1 + u * (-1.0 / 6 +
                           u * (1.0 / 120 +
                                u * (-1.0 / 5040 +
                                     u * (1.0 / 362880 +
                                          u * (-1.0 / 39916800 +
                                               u * (1.0 / 6227020800.0 + u * (-1.0 / 1307674368000.0))))))));
    }
    const d4 dx = sw * w0, dy = sw * w1, dz = sw * w2;
    const d4 nw = qw * cw - qx * dx - qy * dy - qz * dz;
    const d4 nx = qw * dx + qx * cw + qy * dz - qz * dy;
    const d4 ny = qw * dy - qx * dz + qy * cw + qz * dx;
    const d4 nz = qw * dz + qx * dy - qy * dx + qz * cw;
    // Renormalise. q and exp(w / 2) are unit to rounding, so |n|^2 = 1 + d with d ~ 1e-16 and
    // 1 / |n| = 1 - d / 2 to rounding (the next term, 3 d^2 / 8, is below 1e-32); the root and
    // division only for a lane that came in far from unit (|d| > 1e-8: a caller's warm start).
    const d4 n2 = nw * nw + nx * nx + ny * ny + nz * nz;
    d4 norm = 1.5 - 0.5 * n2;
    if (!none(active & (abs(n2 - 1) > 1e-8))) norm = 1 / sqrt(n2);
    qw = select(active, nw * norm, qw), qx = select(active, nx * norm, qx);
    qy = select(active, ny * norm, qy), qz = select(active, nz * norm, qz);
    // Newton converges quadratically: after a step this small the next would be below tolerance.
    active &= ~(newton & (angle2 < tol));
    if (none(active)) break;
  }
  store4(b.q[0], qw), store4(b.q[1], qx), store4(b.q[2], qy), store4(b.q[3], qz);
  const d4 xx = qx * qx, yy = qy * qy, zz = qz * qz, xy = qx * qy, xz = qx * qz, yz = qy * qz;
  const d4 wx = qw * qx, wy = qw * qy, wz = qw * qz;
  store4(b.M[0], 1 - 2 * (yy + zz)), store4(b.M[1], 2 * (xy - wz)), store4(b.M[2], 2 * (xz + wy));
  store4(b.M[3], 2 * (xy + wz)), store4(b.M[4], 1 - 2 * (xx + zz)), store4(b.M[5], 2 * (yz - wx));
  store4(b.M[6], 2 * (xz - wy)), store4(b.M[7], 2 * (yz + wx)), store4(b.M[8], 1 - 2 * (xx + yy));
}

}  // namespace gradel
