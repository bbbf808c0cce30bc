// Stress in physical units (issue 28): an element's small strain relative to its best-fit
// rotation, and the von Mises stress [Pa] of that strain in its region's material.
//
// For an element with current offsets r_i = x_i - c and rest offsets R0_i (element.h):
//   A_pq = sum_i r_i R0_i^T,  A_qq = sum_i R0_i R0_i^T,  F = A_pq A_qq^-1   (the least-squares
//   affine fit of the element's motion, Mueller et al. 2005), M = the best-fit rotation of A_pq
//   (rotation_fit.h, the rotation the elastic force uses), and
//   eps = sym(M^T F) - I   (the small strain in the element's rotated frame).
// A rigid motion gives F = M and eps = 0; a uniform stretch F = diag(1 + e, 1, 1) gives
// eps = diag(e, 0, 0). In 2D (a slab in the x-y plane) A_qq's x-y block is inverted and the
// element is in plane strain (eps_zz = 0).
// The stress is linear isotropic: sigma = lambda tr(eps) I + 2 mu eps with lambda =
// E nu / ((1 + nu)(1 - 2 nu)), mu = E / (2 (1 + nu)); von Mises = sqrt(3/2 s:s), s = dev(sigma).
// E and nu are the element's region's (material.h youngs_modulus, poisson_ratio): the same
// small-strain moduli as its elastic energy.
#pragma once

#include <vector>

#include "gradel/model.h"
#include "gradel/types.h"

namespace gradel {

/// The element's small strain eps (symmetric) about its best-fit rotation; `q` is the rotation's
/// warm start (in) and the fit (out), as elementForces. dim is 2 or 3.
Mat3 elementStrain(int dim, const Vec3* x, const uint32_t* verts, const Vec3* R0, int n, Quat& q);
/// The same from what a caller already has: A (elementCovariance), q fitted to it, and
/// Sinv = restMomentInverse(dim, restSecondMoment(R0, n)).
Mat3 elementStrainOfFit(int dim, const Mat3& A, const Quat& q, const Mat3& Sinv);

/// Von Mises stress [Pa] of a small strain in a linear isotropic material (E [Pa], nu in [0, 0.5)).
Real vonMisesStress(const Mat3& strain, Real youngsModulus, Real poissonRatio);

/// Young's modulus [Pa] of element e: its region's (`consistent` scaling); `paper` scaling, where
/// materials give a force k [N] instead, the modulus of a cube element as stiff as it: 2 k_e / s_e.
Real elementYoungsModulus(const RestModel& model, size_t e);

/// Poisson's ratio of element e: its region's (material.h).
Real elementPoissonRatio(const RestModel& model, size_t e);

/// Von Mises stress [Pa] of element e at positions x in its region's material; `q` as elementStrain.
Real elementVonMises(const RestModel& model, const Vec3* x, size_t e, Quat& q);

/// Von Mises stress [Pa] of every element of the model at `positions`, warm-started from
/// `rotations` (one per element; not changed).
std::vector<Real> elementVonMisesStress(const RestModel& model, const std::vector<Vec3>& positions,
                                        const std::vector<Quat>& rotations);

}  // namespace gradel
