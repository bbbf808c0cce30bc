// coarse_space: the coarse operator E is Z^T A Z of the true Newton matrix A = M / h^2 + K(x)
// (formed here column by column with the element products of element_stiffness.h), symmetric
// positive definite, and the correction Q = Z E^-1 Z^T is exact on the coarse space (Q A Z c = Z c);
// pinned vertices do not move.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>

#include "gradel/coarse_space.h"
#include "gradel/element.h"
#include "gradel/element_stiffness.h"
#include "test_support.h"

namespace gradel {
namespace {

struct Bent {
  test::Body body = test::makeBody("sphere", 8, 3, LayoutKind::Gradational);
  std::vector<Vec3> x;
  std::vector<Quat> q;
  std::vector<StiffnessFrame> frames;
  std::vector<char> free;
  Real h = 1.0 / 120;
  // Bent and twisted about the y axis (rotations of tens of degrees), elements' rotations fitted.
  Bent() {
    const RestModel& m = *body.model;
    const std::vector<Vec3> R0s = m.pairRestOffsets();
    for (const Vec3& p : m.restPositions) {
      const Real a = 8 * p.y(), b = 4 * p.x();
      x.push_back(Eigen::AngleAxisd(a, Vec3::UnitY()) * Eigen::AngleAxisd(b, Vec3::UnitZ()) * p * 1.05);
    }
    q.assign(m.numElements(), Quat::Identity());
    std::vector<Vec3> f;
    for (size_t el = 0; el < m.numElements(); ++el) {
      const uint32_t b0 = m.elemStart[el], n = m.elemStart[el + 1] - b0;
      f.resize(n);
      elementForces(3, x.data(), &m.elemVerts[b0], &R0s[b0], int(n), m.stiffness[el], q[el], f.data(), 50);
      const Mat3 A = elementCovariance(x.data(), &m.elemVerts[b0], &R0s[b0], int(n));
      frames.push_back(elementStiffnessFrame(3, A, q[el], &R0s[b0], int(n)));
    }
    free.assign(m.numVertices(), 1);
    Real yMin = 1e300;
    for (const Vec3& p : m.restPositions) yMin = std::min(yMin, p.y());
    for (size_t i = 0; i < m.numVertices(); ++i)
      if (m.restPositions[i].y() < yMin + 0.015) free[i] = 0;  // the bottom two layers pinned
  }
  // A d on the free vertices (zero on the pinned).
  std::vector<Vec3> apply(const std::vector<Vec3>& d) const {
    const RestModel& m = *body.model;
    const std::vector<Vec3> R0s = m.pairRestOffsets();
    std::vector<Vec3> out(m.numVertices(), Vec3::Zero()), pair(m.numPairs());
    for (size_t el = 0; el < m.numElements(); ++el) {
      const uint32_t b0 = m.elemStart[el], n = m.elemStart[el + 1] - b0;
      elementStiffnessProduct(frames[el], d.data(), &m.elemVerts[b0], &R0s[b0], int(n), m.stiffness[el],
                              &pair[b0]);
      for (uint32_t k = 0; k < n; ++k) out[m.elemVerts[b0 + k]] += pair[b0 + k];
    }
    for (size_t i = 0; i < m.numVertices(); ++i)
      out[i] = free[i] ? Vec3(out[i] + m.mass[i] / (h * h) * d[i]) : Vec3::Zero();
    return out;
  }
};

TEST(CoarseSpace, OperatorIsZtAZAndSymmetricPositiveDefinite) {
  Bent s;
  const RestModel& m = *s.body.model;
  CoarseSpace coarse(m, s.h, s.free, 27);
  coarse.update(s.frames);
  const Eigen::Index n = Eigen::Index(coarse.size());
  ASSERT_EQ(n, 12 * 27);
  const Eigen::MatrixXd E = coarse.matrix();
  Eigen::MatrixXd ref(n, n);
  for (Eigen::Index j = 0; j < n; ++j) {
    Eigen::VectorXd e = Eigen::VectorXd::Zero(n);
    e(j) = 1;
    std::vector<Vec3> z(m.numVertices(), Vec3::Zero());
    coarse.prolongAdd(e, z);
    for (size_t i = 0; i < m.numVertices(); ++i) {
      if (!s.free[i]) {
        EXPECT_EQ(z[i], Vec3::Zero());  // pinned vertices have no coarse motion
      }
    }
    ref.col(j) = coarse.restrictTo(s.apply(z));
  }
  const Real scale = ref.diagonal().maxCoeff();
  // Equal up to rounding and the relative 1e-10 added to the diagonal (a unit diagonal on columns without support).
  Eigen::MatrixXd diff = E - ref;
  for (Eigen::Index j = 0; j < n; ++j)
    if (ref(j, j) <= 1e-14 * scale) diff(j, j) = 0;
  EXPECT_LT(diff.cwiseAbs().maxCoeff(), 1e-8 * scale);
  EXPECT_LT((E - E.transpose()).cwiseAbs().maxCoeff(), 1e-12 * scale);
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(E);
  EXPECT_GT(eig.eigenvalues().minCoeff(), 0);
  // The rotation term matters: E differs from the constant Z^T P Z (P the projective matrix).
  CoarseSpace atRest(m, s.h, s.free, 27);
  EXPECT_GT((atRest.matrix() - E).cwiseAbs().maxCoeff(), 1e-3 * scale);
}

TEST(CoarseSpace, CorrectionIsExactOnTheCoarseSpace) {
  Bent s;
  const RestModel& m = *s.body.model;
  CoarseSpace coarse(m, s.h, s.free, 27);
  coarse.update(s.frames);
  Eigen::VectorXd c = Eigen::VectorXd::LinSpaced(Eigen::Index(coarse.size()), -1, 1).array().sin();
  std::vector<Vec3> z(m.numVertices(), Vec3::Zero());
  coarse.prolongAdd(c, z);
  std::vector<Vec3> back(m.numVertices(), Vec3::Zero());
  coarse.addCorrection(s.apply(z), back);  // Q A Z c
  Real err = 0, size = 0;
  for (size_t i = 0; i < m.numVertices(); ++i)
    err = std::max(err, (back[i] - z[i]).norm()), size = std::max(size, z[i].norm());
  EXPECT_GT(size, 0.1);
  EXPECT_LT(err, 1e-6 * size);
}

// Eigen sizes the blocks of its dense products and of LLT's rank updates from the CPU's cache
// sizes, which decide the order of each sum; the coarse space pins them, so its correction has
// the same bits on every machine (tests/golden's large-step hashes differed between two CI
// machines of the same flavour before).
TEST(CoarseSpace, CorrectionBitsDoNotDependOnTheCpuCaches) {
  Bent s;
  const RestModel& m = *s.body.model;
  const std::vector<Vec3> r(m.numVertices(), Vec3(0.3, -0.2, 0.1));
  const std::ptrdiff_t native[3] = {Eigen::l1CacheSize(), Eigen::l2CacheSize(), Eigen::l3CacheSize()};
  auto correction = [&](std::ptrdiff_t l1, std::ptrdiff_t l2, std::ptrdiff_t l3) {
    Eigen::setCpuCacheSizes(l1, l2, l3);  // as another CPU would report them
    CoarseSpace coarse(m, s.h, s.free, 64);
    coarse.update(s.frames);
    std::vector<Vec3> z(m.numVertices(), Vec3::Zero());
    coarse.addCorrection(r, z);
    return z;
  };
  const std::vector<Vec3> small = correction(8 << 10, 64 << 10, 1 << 20);
  const std::vector<Vec3> large = correction(64 << 10, 2 << 20, 64 << 20);
  Eigen::setCpuCacheSizes(native[0], native[1], native[2]);
  size_t differ = 0;
  for (size_t i = 0; i < m.numVertices(); ++i) differ += small[i] != large[i];
  EXPECT_EQ(differ, 0u) << "of " << m.numVertices() << " vertices";
  EXPECT_GT(small[0].norm() + small.back().norm(), 0);
}

}  // namespace
}  // namespace gradel
