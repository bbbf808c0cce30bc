// The shape-matching element's stiffness (the Hessian of element.h's energy) applied to a
// displacement, for the large step's Newton solve (large_step.h): a pure kernel.
//
// With R0'_i = R0_i - mean R0 (the rest offsets, summing to zero), A = sum_i x_i R0'_i^T and M its
// polar rotation (M maximises tr(M^T A)), the element energy is
//   E = k/2 (sum |R0'_i|^2 + sum |r_i|^2) - k tr(M^T A),   f_i = k (M R0'_i - r_i).
// Along a displacement p, with S = M^T A (symmetric) and T = tr(S) I - S,
//   dA = sum_i p_i R0'_i^T,  b = vee(M^T dA - dA^T M) = sum_i R0'_i x (M^T p_i),  w = T^-1 b,
//   dM = M [w]x  (the derivative of the polar rotation),
//   (K p)_i = -df_i = k ((p_i - mean p) - M (w x R0'_i)).
// Definiteness: p^T K p = k (|G p|^2 - b^T T^-1 b), G the centring. With T0 = tr(C) I - C,
// C = sum R0'_i R0'_i^T the rest covariance, the b of all p with |G p| = 1 fill the ellipsoid
// b^T T0^-1 b <= 1, so K >= 0 exactly when T >= T0: true at rest (T = T0: the rotations are the
// null modes) and for stretched elements, false for compressed or inverted ones, where Newton's
// system would be indefinite. The frame therefore uses T' = T0^1/2 max(T0^-1/2 T T0^-1/2, I) T0^1/2
// (eigenvalues clamped at 1): the nearest T' >= T that keeps the element's matrix positive
// semidefinite, and between the exact Hessian and the fixed-rotation one (0 <= K' <= k G^T G, the
// projective-dynamics matrix, projective.h). In 2D only the rotation about z exists: T is the
// scalar S_xx + S_yy.
// Per-pair weights w_i (E = k/2 sum w_i |M R0_i - r_i|^2 about the weighted centroid) would enter
// as w_i in dA, b, C, the mean of p and the output: the structure stays the same.
#pragma once

#include "gradel/types.h"

namespace gradel {

/// What the product needs of an element at the current positions: its rotation M and the
/// clamped T'^-1 (see above).
struct StiffnessFrame {
  Mat3 M = Mat3::Identity();
  Mat3 Tinv = Mat3::Zero();
};

/// The frame of an element with covariance A (element.h elementCovariance) and fitted rotation q.
StiffnessFrame elementStiffnessFrame(int dim, const Mat3& A, const Quat& q, const Vec3* R0, int n);

/// The frame at rest (positions at their rest offsets, q = identity): there A = C, so T = T0 and
/// the clamp is the identity, T'^-1 = T0^-1 (a 3x3 inverse where T0 is clearly not flat, else one
/// symmetric eigensolve; no covariance). Equal to elementStiffnessFrame(dim, C, identity, R0, n)
/// to rounding.
StiffnessFrame elementRestStiffnessFrame(int dim, const Vec3* R0, int n);

/// out[i] = (K p)_i for the element's n vertices (p read at verts[i]).
void elementStiffnessProduct(const StiffnessFrame& frame, const Vec3* p, const uint32_t* verts, const Vec3* R0, int n,
                             Real k, Vec3* out);

}  // namespace gradel
