#include "gradel/element_strain.h"

#include <cmath>
#include <stdexcept>

#include <Eigen/Eigenvalues>

#include "gradel/element.h"
#include "gradel/material.h"
#include "gradel/rotation_fit.h"

namespace gradel {

Mat3 elementStrain(int dim, const Vec3* x, const uint32_t* verts, const Vec3* R0, int n, Quat& q) {
  const Mat3 A = elementCovariance(x, verts, R0, n);
  if (dim == 2) {
    q = Quat(Eigen::AngleAxisd(fitRotation2(A), Vec3::UnitZ()));
  } else {
    fitRotation3(A, q, 20, 1e-12);
  }
  return elementStrainOfFit(dim, A, q, restMomentInverse(dim, restSecondMoment(R0, size_t(n))));
}

Mat3 elementStrainOfFit(int dim, const Mat3& A, const Quat& q, const Mat3& Sinv) {
  Mat3 F = A * Sinv;
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

Real elementPoissonRatio(const RestModel& m, size_t e) {
  const MaterialSettings& mat = m.materials.empty() ? m.material : m.materials[m.elementMaterial[e]];
  return mat.poissonRatio;
}

Real elementVonMises(const RestModel& m, const Vec3* x, size_t e, Quat& q) {
  const uint32_t b = m.elemStart[e], n = m.elemStart[e + 1] - b;
  thread_local std::vector<Vec3> R0;  // (its storage reused from element to element on each thread)
  const Mat3 eps = elementStrain(m.dim, x, &m.elemVerts[b], m.restOffsets(e, R0), int(n), q);
  return vonMisesStress(eps, elementYoungsModulus(m, e), elementPoissonRatio(m, e));
}

std::vector<Real> elementVonMisesStress(const RestModel& m, const std::vector<Vec3>& positions,
                                        const std::vector<Quat>& rotations) {
  if (positions.size() != m.numVertices() || rotations.size() != m.numElements())
    throw std::invalid_argument("elementVonMisesStress: one position per vertex and one rotation per element");
  std::vector<Real> s(m.numElements());
  for (size_t e = 0; e < s.size(); ++e) {
    Quat q = rotations[e];
    s[e] = elementVonMises(m, positions.data(), e, q);
  }
  return s;
}

}  // namespace gradel
