#include "gradel/element_strain.h"

#include <cmath>
#include <stdexcept>

#include <Eigen/Eigenvalues>

#include "gradel/element.h"
#include "gradel/material.h"
#include "gradel/rotation_fit.h"

namespace gradel {

namespace {

// A_qq^-1: the 2x2 block in 2D (z zero), the 3x3 matrix in 3D; a pseudo-inverse for a
// degenerate rest shape (never for the layouts' elements, whose cells are full squares / cubes).
Mat3 restMomentInverse(int dim, const Mat3& S) {
  Mat3 inv = Mat3::Zero();
  if (dim == 2) {
    const Real det = S(0, 0) * S(1, 1) - S(0, 1) * S(1, 0);
    if (std::abs(det) > 1e-30 * (S(0, 0) * S(1, 1) + 1e-300)) {
      inv(0, 0) = S(1, 1) / det, inv(1, 1) = S(0, 0) / det;
      inv(0, 1) = -S(0, 1) / det, inv(1, 0) = -S(1, 0) / det;
      return inv;
    }
  } else if (std::abs(S.determinant()) > 1e-30 * std::pow(S.trace() / 3 + 1e-300, 3)) {
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

}  // namespace

Mat3 elementStrain(int dim, const Vec3* x, const uint32_t* verts, const Vec3* R0, int n, Quat& q) {
  const Mat3 A = elementCovariance(x, verts, R0, n);
  if (dim == 2) {
    q = Quat(Eigen::AngleAxisd(fitRotation2(A), Vec3::UnitZ()));
  } else {
    fitRotation3(A, q, 20, 1e-12);
  }
  Mat3 F = A * restMomentInverse(dim, restSecondMoment(R0, size_t(n)));
  if (dim == 2) F.row(2).setZero(), F.col(2).setZero(), F(2, 2) = 1;
  const Mat3 G = q.toRotationMatrix().transpose() * F;
  return Real(0.5) * (G + G.transpose()) - Mat3::Identity();
}

Real vonMisesStress(const Mat3& strain, Real E, Real nu) {
  if (!(nu >= 0 && nu < 0.5)) throw std::invalid_argument("vonMisesStress: Poisson's ratio must be in [0, 0.5)");
  const Real lambda = E * nu / ((1 + nu) * (1 - 2 * nu)), mu = E / (2 * (1 + nu));
  const Mat3 sigma = lambda * strain.trace() * Mat3::Identity() + 2 * mu * strain;
  const Mat3 s = sigma - sigma.trace() / 3 * Mat3::Identity();
  return std::sqrt(1.5 * s.squaredNorm());
}

Real elementYoungsModulus(const RestModel& m, size_t e) {
  const MaterialSettings& mat = m.materials.empty() ? m.material : m.materials[m.elementMaterial[e]];
  if (mat.scaling == Scaling::Paper) return 2 * m.stiffness[e] / m.size[e];
  return mat.youngsModulus;
}

Real elementVonMises(const RestModel& m, const Vec3* x, size_t e, Quat& q, Real poissonRatio) {
  const uint32_t b = m.elemStart[e], n = m.elemStart[e + 1] - b;
  const Mat3 eps = elementStrain(m.dim, x, &m.elemVerts[b], &m.restOffsets[b], int(n), q);
  return vonMisesStress(eps, elementYoungsModulus(m, e), poissonRatio);
}

std::vector<Real> elementVonMisesStress(const RestModel& m, const std::vector<Vec3>& positions,
                                        const std::vector<Quat>& rotations, Real poissonRatio) {
  if (positions.size() != m.numVertices() || rotations.size() != m.numElements())
    throw std::invalid_argument("elementVonMisesStress: one position per vertex and one rotation per element");
  std::vector<Real> s(m.numElements());
  for (size_t e = 0; e < s.size(); ++e) {
    Quat q = rotations[e];
    s[e] = elementVonMises(m, positions.data(), e, q, poissonRatio);
  }
  return s;
}

}  // namespace gradel
