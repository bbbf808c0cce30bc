// Best-fit rotation of an element's rest shape (paper eq. 1).
//
// Eq. 1 asks for the rotation M with sum_i r_i x (M R0_i) = 0; that is the rotation factor of
// the polar decomposition of A = sum_i r_i R0_i^T, i.e. the proper rotation maximising
// tr(M^T A). We find it iteratively on the rotation group: Newton steps where the objective is
// locally concave, else the step of Mueller, Bender, Chentanez, Macklin 2016 ("A robust method to
// extract the rotational part of deformations"). Warm-started from the previous step's rotation
// it converges in one or two iterations, and it always returns a proper rotation (det +1), also
// for flat (rank-deficient) or inverted (det A < 0) elements.
#pragma once

#include "gradel/types.h"

namespace gradel {

/// 3D: refines `q` (unit quaternion, in/out) towards the rotation maximising tr(M^T A).
/// Stops after maxIterations or when the correction angle falls below `tolerance` [rad].
/// Returns the number of iterations used.
int fitRotation3(const Mat3& A, Quat& q, int maxIterations = 20, Real tolerance = 1e-12);

/// Four 3D fits at once (structure of arrays, one lane per element): exactly fitRotation3's
/// iteration in every lane (Newton or Mueller step, trust region, the same stopping rules), with
/// sin/cos of the step from their series (exact to rounding for the trust region's angles):
/// to h^14, or to h^6 when every active lane of the batch turns by less than 0.01 rad (the usual
/// case with a warm start; the terms left out are below 1e-23), and the quaternion renormalised
/// to first order unless a lane came in more than 1e-8 from unit. Lanes stop independently; the
/// series' length is the batch's, so a lane's last bit can depend on the other lanes, never its
/// accuracy; batches are fixed by the element order, so results are the same at any thread
/// count. A lane with A = identity and q = identity is a no-op (use it to pad a short batch).
constexpr int kRotationLanes = 4;
struct RotationBatch {
  alignas(32) Real A[9][kRotationLanes];  ///< A(r, c) at [3 r + c].
  alignas(32) Real q[4][kRotationLanes];  ///< In: warm start, out: fit; w, x, y, z.
  alignas(32) Real M[9][kRotationLanes];  ///< Out: the rotation matrix of q, M(r, c) at [3 r + c].
};
void fitRotation3Batch(RotationBatch& batch, int maxIterations = 20, Real tolerance = 1e-12);

/// 3D without a warm start: a robust cold start (the rotation of the SVD, sign-corrected to
/// det +1) refined by fitRotation3. Used at initialisation and by tests.
Quat fitRotation3Cold(const Mat3& A);

/// 2D (rotation about z): the closed-form angle maximising tr(M^T A) for the upper-left 2x2 of A,
/// theta = atan2(A10 - A01, A00 + A11). Always proper; A == 0 gives 0.
Real fitRotation2(const Mat3& A);

}  // namespace gradel
