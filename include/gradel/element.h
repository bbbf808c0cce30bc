// The local shape-preserving element (paper sec. 2.2, eq. 1, fig. 3): a pure kernel.
//
// For one element with vertices x_i (world), rest offsets R0_i (relative to the rest centroid)
// and stiffness k_e [N/m]:
//   c   = mean of x_i                    (unweighted centroid, as in the paper)
//   r_i = x_i - c
//   A   = sum_i r_i R0_i^T;  M = best-fit proper rotation of A (rotation_fit.h)
//   f_i = k_e (M R0_i - r_i)            forces sum to zero and have zero torque (eq. 1)
//   E   = k_e / 2 sum_i |M R0_i - r_i|^2  (f_i = -dE/dx_i: the elastic energy)
// This is the reference form (metrics, stress, tests); the explicit step runs the same element in
// element_stage.h's data-parallel layout.
//
// The volumetric term (material.h, Poisson's ratio nu > 0): with M the element's best-fit
// rotation above, S = sum_i R0_i R0_i^T, D the dimension (3, or 2 in 2D) and F = A S^-1 the
// element's affine fit,
//   e_v = tr(M_F^T F) - D                  (the volumetric strain in the element's rotated frame:
//                                            tr(eps) for a small strain eps)
//   E_v = kappa_e / 2 e_v^2
//   f_i = -dE_v/dx_i = -kappa_e e_v M_F V R0_i
// with V = S^-1 (volumeStrainMatrix; in 2D the x-y block) and M_F the best-fit rotation of F
// (not of A: M_F maximises tr(M^T F), so d tr(M_F^T F) / dF = M_F, and the forces are the exact
// gradient with zero torque, sum r_i (M_F V R0_i)^T = F M_F^T being symmetric; M of A would leave
// a torque of second order in the strain). A complete element without hanging vertices has an
// isotropic S = (tr S / D) I, V = (D / tr S) I, M_F = M, and the term is computed in that scalar
// form: e_v = D (tr(M^T A) - tr S) / tr S. An incomplete element (a line or plate of cells) or one
// carrying hanging vertices on some faces has an anisotropic S; the scalar form there weighed each
// strain by S (a plate of 2 x 2 x 1 cells: its in-plane strains 1.26x, its normal one 0.47x), which
// made a gradational bar 1.11 / 1.19 / 1.22 x stiffer than E in tension at nu = 0.3 / 0.45 / 0.49,
// with a lateral / axial ratio of 0.37 / 0.56 / 0.62 (docs/validation/poisson.md before
// 2026-11-28). In the scalar form:
// M maximises tr(M^T A) over rotations, so d tr(M^T A) / dA = M (the envelope theorem: M's own
// change does not count) and dA/dx_i [u] = u R0_i^T. The forces sum to zero (sum R0_i = 0; the
// rounding residue's share removed as above) and have zero torque for the same reason as eq. 1
// (sum r_i (M R0_i)^T = A M^T is symmetric for the polar rotation). This is the corotated linear
// volumetric energy (the stress output's eps = sym(M^T F) - I, element_strain.h): its stiffness
// along the forces' direction is kappa_e D^2 / tr S in every pose, like the rotation term's k_e
// (so the rest estimate of the explicit step's limit holds when deformed), and it stays restoring
// through inversion: an element turned inside out has tr(M^T A) < tr S, and the force pushes it
// back out along M R0_i, the rotation term's own target. (J - 1)^2 on J = det F was tried first:
// its stiffness grows with J^(4/3), and a mirrored 4-voxel box at nu = 0.3 overshot to J = 3 and
// blew up the explicit step within 20 steps, where nu = 0 recovered.
#pragma once

#include "gradel/types.h"

namespace gradel {

struct ElementResult {
  Real energy = 0;     ///< [J] elastic energy of the element.
  Real sumSqDisp = 0;  ///< [m^2] sum_i |M R0_i - r_i|^2 (stress = sqrt(sumSqDisp / n) / size).
};

/// Computes the element's forces into f[0..n). `x` is the global position array, `verts` the
/// element's vertex ids, `R0` its rest offsets, `q` the rotation (in: warm start, out: fit; in 2D
/// a rotation about z). dim is 2 or 3. maxIterations bounds the 3D rotation refinement.
ElementResult elementForces(int dim, const Vec3* x, const uint32_t* verts, const Vec3* R0, int n, Real k, Quat& q,
                            Vec3* f, int maxIterations = 4);

/// A = sum_i r_i R0_i^T about the current centroid (also returns the centroid).
Mat3 elementCovariance(const Vec3* x, const uint32_t* verts, const Vec3* R0, int n, Vec3* centroid = nullptr);

/// S^-1 for S = sum R0_i R0_i^T: the 2x2 block in 2D (z row and column zero), the 3x3 inverse in
/// 3D; a pseudo-inverse for a degenerate rest shape (never for the layouts' elements).
Mat3 restMomentInverse(int dim, const Mat3& S);

/// The volumetric term above: adds its forces into f[0..n) and returns its energy [J]. `q` is the
/// element's fitted rotation (elementForces' output), `kappa` [J] = lambda V_e (material.h
/// elementVolumeStiffness).
Real elementVolumeForces(int dim, const Vec3* x, const uint32_t* verts, const Vec3* R0, int n, const Quat& q,
                         Real kappa, Vec3* f);
/// tr S = sum_i |R0_i|^2 [m^2] (the term's normalisation).
Real restMomentTrace(const Vec3* R0, int n);
/// The volumetric term's V = S^-1 above [1/m^2], when S is not isotropic: returns true and sets
/// V (in 2D the x-y block, z row and column zero). Returns false for an isotropic S (exactly:
/// zero off-diagonals and equal diagonal entries), where V = (D / tr S) I and every user keeps
/// that scalar form.
bool volumeStrainMatrix(int dim, const Vec3* R0, int n, Mat3& V);
/// M_F above: the best-fit proper rotation of F (3D: fitRotation3 warm-started from `warm`, the
/// element's rotation of A, to 1e-12; 2D: the closed form about z).
Mat3 fitAffineRotation(int dim, const Mat3& F, const Quat& warm);

/// F = A S^-1 (F_zz = 1 in 2D) and its cofactor matrix cof(F) = dJ/dF.
Mat3 elementDeformationGradient(int dim, const Mat3& A, const Mat3& Sinv);
Mat3 cofactor(const Mat3& F);

/// Deformation gradient determinant estimate det(A) / det(sum R0 R0^T); < 0 means inverted.
Real elementDeterminant(int dim, const Vec3* x, const uint32_t* verts, const Vec3* R0, int n);
/// The same from A (elementCovariance) and S = sum R0 R0^T (restSecondMoment) already formed.
Real deformationDeterminant(int dim, const Mat3& A, const Mat3& S);

}  // namespace gradel
