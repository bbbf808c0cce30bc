// rotation_fit: the best-fit rotation of eq. 1 is recovered, and is always proper.
#include <gtest/gtest.h>
#include <rapidcheck/gtest.h>

#include <random>

#include "gradel/rotation_fit.h"

using namespace gradel;

namespace {
Quat randomRotation(std::mt19937& rng) {
  std::normal_distribution<double> n(0, 1);
  Quat q(n(rng), n(rng), n(rng), n(rng));
  q.normalize();
  return q;
}
Mat3 randomSpd(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1, 1);
  Mat3 B;
  for (int i = 0; i < 9; ++i) B.data()[i] = u(rng);
  return B * B.transpose() + 0.2 * Mat3::Identity();
}
bool isProperRotation(const Mat3& R, double tol = 1e-9) {
  return (R * R.transpose() - Mat3::Identity()).norm() < tol && std::abs(R.determinant() - 1) < tol;
}
}  // namespace

TEST(RotationFit, ColdFitRecoversRandomRotations) {
  std::mt19937 rng(1);
  for (int t = 0; t < 500; ++t) {
    const Quat q = randomRotation(rng);
    const Mat3 A = q.toRotationMatrix() * randomSpd(rng);  // polar decomposition R S
    const Quat fit = fitRotation3Cold(A);
    EXPECT_LT((fit.toRotationMatrix() - q.toRotationMatrix()).norm(), 1e-6) << "trial " << t;
  }
}

TEST(RotationFit, WarmStartConvergesInFewIterations) {
  std::mt19937 rng(2);
  for (int t = 0; t < 200; ++t) {
    const Quat q = randomRotation(rng);
    const Mat3 A = q.toRotationMatrix() * randomSpd(rng);
    // A warm start 0.05 rad away, as after one time step of a spinning element.
    Quat warm = Quat(Eigen::AngleAxisd(0.05, Vec3(1, 2, 3).normalized())) * q;
    const int iters = fitRotation3(A, warm, 20, 1e-10);
    EXPECT_LE(iters, 12);
    EXPECT_LT((warm.toRotationMatrix() - q.toRotationMatrix()).norm(), 1e-6);
  }
}

TEST(RotationFit, EquationOneMomentsBalance) {
  // sum_i r_i x (M R0_i) = 0  <=>  A M^T is symmetric.
  std::mt19937 rng(3);
  for (int t = 0; t < 100; ++t) {
    Mat3 A;
    std::uniform_real_distribution<double> u(-1, 1);
    for (int i = 0; i < 9; ++i) A.data()[i] = u(rng);
    const Mat3 M = fitRotation3Cold(A).toRotationMatrix();
    const Mat3 S = A * M.transpose();
    EXPECT_LT((S - S.transpose()).norm(), 1e-8 * (1 + A.norm()));
  }
}

TEST(RotationFit, FlatElementGivesProperRotation) {
  // All rest offsets in the xy plane: A has rank 2.
  const Quat q(Eigen::AngleAxisd(0.7, Vec3(0.3, -1, 0.4).normalized()));
  Mat3 S = Mat3::Zero();
  S(0, 0) = 2, S(1, 1) = 1;
  const Mat3 A = q.toRotationMatrix() * S;
  const Mat3 M = fitRotation3Cold(A).toRotationMatrix();
  EXPECT_TRUE(isProperRotation(M));
  // The two spanned directions are still recovered.
  EXPECT_LT((M.leftCols<2>() - q.toRotationMatrix().leftCols<2>()).norm(), 1e-6);
  Quat warm = Quat::Identity();
  fitRotation3(A, warm);
  EXPECT_TRUE(isProperRotation(warm.toRotationMatrix()));
}

TEST(RotationFit, InvertedElementGivesProperRotation) {
  std::mt19937 rng(4);
  for (int t = 0; t < 200; ++t) {
    const Mat3 reflect = Vec3(1, 1, -1).asDiagonal();
    const Mat3 A = randomRotation(rng).toRotationMatrix() * reflect * randomSpd(rng);
    ASSERT_LT(A.determinant(), 0);
    EXPECT_TRUE(isProperRotation(fitRotation3Cold(A).toRotationMatrix()));
    Quat warm = randomRotation(rng);
    fitRotation3(A, warm, 20);
    EXPECT_TRUE(isProperRotation(warm.toRotationMatrix()));
  }
  Quat z = Quat::Identity();
  fitRotation3(Mat3::Zero(), z);
  EXPECT_TRUE(isProperRotation(z.toRotationMatrix()));
}

RC_GTEST_PROP(RotationFit, TwoDimensionalAngleRecovered, ()) {
  const double angle = *rc::gen::inRange(-3140, 3140) / 1000.0;
  const double sx = 0.1 + *rc::gen::inRange(0, 100) / 20.0, sy = 0.1 + *rc::gen::inRange(0, 100) / 20.0;
  Mat3 A = Mat3::Zero();
  const Mat3 R = Eigen::AngleAxisd(angle, Vec3::UnitZ()).toRotationMatrix();
  A.topLeftCorner<2, 2>() = R.topLeftCorner<2, 2>() * Eigen::Vector2d(sx, sy).asDiagonal();
  RC_ASSERT(std::abs(std::remainder(fitRotation2(A) - angle, 2 * M_PI)) < 1e-9);
}

TEST(RotationFit, TwoDimensionalInvertedIsStillARotation) {
  Mat3 A = Mat3::Zero();
  A(0, 0) = -1, A(1, 1) = 1;  // mirrored element
  const double th = fitRotation2(A);
  EXPECT_TRUE(std::isfinite(th));
  EXPECT_EQ(fitRotation2(Mat3::Zero()), 0.0);
}
