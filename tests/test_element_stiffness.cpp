// element_stiffness: the analytic K p of the shape-matching element against a central difference
// of its forces (where the clamp is inactive), the rotations as null modes, and K >= 0 always.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cstdio>
#include <random>

#include "gradel/element.h"
#include "gradel/element_stiffness.h"
#include "gradel/rotation_fit.h"

using namespace gradel;

namespace {

struct Cube {
  std::vector<Vec3> R0;
  std::vector<uint32_t> ids;
  std::vector<Vec3> x;
};
// A unit cube's corners plus a hanging vertex on one face (an element of the gradational layout).
Cube cube(const Mat3& F) {
  Cube c;
  std::vector<Vec3> rest;
  for (int i = 0; i < 8; ++i) rest.emplace_back(i & 1, (i >> 1) & 1, (i >> 2) & 1);
  rest.emplace_back(0.5, 0.5, 0);
  Vec3 m = Vec3::Zero();
  for (const Vec3& p : rest) m += p;
  m /= Real(rest.size());
  for (size_t i = 0; i < rest.size(); ++i)
    c.R0.push_back(rest[i] - m), c.ids.push_back(uint32_t(i)), c.x.push_back(F * rest[i] + Vec3(0.3, -0.2, 0.1));
  return c;
}

std::vector<Vec3> product(const Cube& c, const std::vector<Vec3>& p, Real k, Quat& q) {
  std::vector<Vec3> f(c.x.size()), out(c.x.size());
  elementForces(3, c.x.data(), c.ids.data(), c.R0.data(), int(c.x.size()), k, q, f.data(), 50);
  const Mat3 A = elementCovariance(c.x.data(), c.ids.data(), c.R0.data(), int(c.x.size()));
  const StiffnessFrame fr = elementStiffnessFrame(3, A, q, c.R0.data(), int(c.x.size()));
  elementStiffnessProduct(fr, p.data(), c.ids.data(), c.R0.data(), int(c.x.size()), k, out.data());
  return out;
}

Mat3 rotated(const Mat3& stretch) {
  return Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized()).toRotationMatrix() * stretch;
}

TEST(ElementStiffness, MatchesTheForcesCentralDifferenceWhenStretched) {
  Mat3 S;
  S << 1.2, 0.05, 0, 0.05, 1.1, 0.02, 0, 0.02, 1.15;  // stretched: T >= T0, the exact Hessian
  Cube c = cube(rotated(S));
  std::mt19937 rng(3);
  std::uniform_real_distribution<Real> u(-1, 1);
  std::vector<Vec3> p(c.x.size());
  for (Vec3& v : p) v = Vec3(u(rng), u(rng), u(rng));
  const Real k = 1000;
  Quat q = Quat::Identity();
  const std::vector<Vec3> Kp = product(c, p, k, q);
  const Real eps = 1e-6;
  std::vector<Vec3> fPlus(c.x.size()), fMinus(c.x.size());
  Cube plus = c, minus = c;
  for (size_t i = 0; i < c.x.size(); ++i) plus.x[i] += eps * p[i], minus.x[i] -= eps * p[i];
  Quat qp = q, qm = q;
  elementForces(3, plus.x.data(), c.ids.data(), c.R0.data(), int(c.x.size()), k, qp, fPlus.data(), 50);
  elementForces(3, minus.x.data(), c.ids.data(), c.R0.data(), int(c.x.size()), k, qm, fMinus.data(), 50);
  Real scale = 0;
  for (const Vec3& v : Kp) scale = std::max(scale, v.norm());
  ASSERT_GT(scale, 1.0);
  for (size_t i = 0; i < c.x.size(); ++i) {
    const Vec3 fd = -(fPlus[i] - fMinus[i]) / (2 * eps);
    EXPECT_LT((fd - Kp[i]).norm(), 1e-6 * scale) << i;
  }
}

TEST(ElementStiffness, RotationsAndTranslationsAreNullModesAtRest) {
  Cube c = cube(rotated(Mat3::Identity()));
  Quat q = Quat::Identity();
  const Vec3 w(0.3, -1.1, 0.4), t(1, 2, 3);
  Vec3 centre = Vec3::Zero();
  for (const Vec3& x : c.x) centre += x;
  centre /= Real(c.x.size());
  std::vector<Vec3> p;
  for (const Vec3& x : c.x) p.push_back(w.cross(x - centre) + t);
  for (const Vec3& v : product(c, p, 1000, q)) EXPECT_LT(v.norm(), 1e-9);
}

TEST(ElementStiffness, PositiveSemidefiniteWhenCompressedOrInverted) {
  // The element's 27 x 27 matrix, column by column; its smallest eigenvalue. Without the clamp it
  // is -0.33 k when compressed to half (the exact Hessian is indefinite there).
  for (Real s : {0.5, 0.2, -0.3}) {  // compressed along x, and inverted
    Mat3 F = Mat3::Identity();
    F(0, 0) = s;
    Cube c = cube(rotated(F));
    Quat q = Quat::Identity();
    const int n = int(c.x.size());
    Eigen::MatrixXd K(3 * n, 3 * n);
    for (int j = 0; j < 3 * n; ++j) {
      std::vector<Vec3> p(size_t(n), Vec3::Zero());
      p[size_t(j / 3)][j % 3] = 1;
      const std::vector<Vec3> Kp = product(c, p, 1.0, q);
      for (int i = 0; i < n; ++i) K.block<3, 1>(3 * i, j) = Kp[size_t(i)];
    }
    EXPECT_LT((K - K.transpose()).norm(), 1e-12 * K.norm());
    const Real lowest = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(0.5 * (K + K.transpose())).eigenvalues()(0);
    std::printf("stretch %.1f: lowest eigenvalue %.3g k\n", s, lowest);
    EXPECT_GE(lowest, -1e-12) << "stretch " << s;
  }
}

}  // namespace

// The frame at rest made directly (T0^-1) is the general frame at the rest positions to rounding,
// in 3D (a cube with a hanging vertex, an incomplete element) and 2D, and a flat element (its
// offsets on a line) has no rotation term either way.
TEST(ElementStiffness, RestFrameIsTheGeneralFrameAtRest) {
  const Cube c = cube(Mat3::Identity());
  std::vector<Vec3> partial(c.R0.begin(), c.R0.begin() + 5);
  Vec3 m = Vec3::Zero();
  for (const Vec3& p : partial) m += p;
  for (Vec3& p : partial) p -= m / Real(partial.size());
  std::vector<Vec3> line = {Vec3(-1, 0, 0), Vec3(0, 0, 0), Vec3(1, 0, 0)};
  for (int dim : {2, 3})
    for (const std::vector<Vec3>* R0 : std::vector<const std::vector<Vec3>*>{&c.R0, &partial, &line}) {
      const int n = int(R0->size());
      std::vector<uint32_t> ids(n);
      for (int i = 0; i < n; ++i) ids[i] = uint32_t(i);
      const Mat3 A = elementCovariance(R0->data(), ids.data(), R0->data(), n);  // rest positions = offsets
      const StiffnessFrame general = elementStiffnessFrame(dim, A, Quat::Identity(), R0->data(), n);
      const StiffnessFrame rest = elementRestStiffnessFrame(dim, R0->data(), n);
      EXPECT_TRUE(rest.M.isIdentity(0));
      EXPECT_LE((rest.Tinv - general.Tinv).norm(), 1e-12 * std::max(Real(1), general.Tinv.norm()));
    }
}
