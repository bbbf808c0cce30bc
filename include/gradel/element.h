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

/// Deformation gradient determinant estimate det(A) / det(sum R0 R0^T); < 0 means inverted.
Real elementDeterminant(int dim, const Vec3* x, const uint32_t* verts, const Vec3* R0, int n);

}  // namespace gradel
