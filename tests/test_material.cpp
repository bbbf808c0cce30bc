// material.h: the stiffness and mass rules of the two scalings, as pure functions.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "gradel/material.h"

using namespace gradel;

namespace {
// The rest offsets of the corners of an axis-aligned box of edges (a, b, c) about its centre;
// 2D: the four corners of an a x b rectangle.
std::vector<Vec3> boxCorners(Vec3 edge, int dim) {
  std::vector<Vec3> r;
  for (int k = 0; k < (dim == 3 ? 2 : 1); ++k)
    for (int j = 0; j < 2; ++j)
      for (int i = 0; i < 2; ++i)
        r.push_back(Vec3((i - 0.5) * edge.x(), (j - 0.5) * edge.y(), dim == 3 ? (k - 0.5) * edge.z() : 0));
  return r;
}
// Energy k/2 tr(eps S eps^T) of an element with stiffness k under a uniform strain eps.
Real elementEnergy(Real k, const std::vector<Vec3>& r, const Mat3& eps) {
  Real e = 0;
  for (const Vec3& x : r) e += 0.5 * k * (eps * x).squaredNorm();
  return e;
}
}  // namespace

// A complete cube element of edge s: k_e = E s / 2, exact for every uniform strain (its energy is
// the continuum's E/2 |eps|^2 V for a shear and a stretch alike); 2D square, one voxel thick: E h.
TEST(Material, ConsistentCompleteElementIsExact) {
  MaterialSettings m;
  m.youngsModulus = 3e5;
  const Real h = 0.01;
  const int edge = 4;  // voxels
  const Real s = edge * h;
  const auto r3 = boxCorners(Vec3(s, s, s), 3);
  const Real k3 = elementStiffness(m, 3, h, int64_t(edge) * edge * edge, s, r3.data(), r3.size());
  EXPECT_NEAR(k3, m.youngsModulus * s / 2, 1e-9 * k3);
  Mat3 stretch = Mat3::Zero(), shear = Mat3::Zero();
  stretch(0, 0) = 0.01, shear(0, 1) = 0.01;
  for (const Mat3& eps : {stretch, shear})
    EXPECT_NEAR(elementEnergy(k3, r3, eps), 0.5 * m.youngsModulus * eps.squaredNorm() * s * s * s, 1e-12);

  const auto r2 = boxCorners(Vec3(s, s, 0), 2);
  const Real k2 = elementStiffness(m, 2, h, int64_t(edge) * edge, s, r2.data(), r2.size());
  EXPECT_NEAR(k2, m.youngsModulus * h, 1e-9 * k2);
}

// A line of two unit cells (an incomplete element; its 12 vertices, the shared face's included):
// exact along its axis, softer (3/8) across it, never stiffer than the continuum.
TEST(Material, ConsistentIncompleteElementNeverStiffer) {
  MaterialSettings m;
  const Real h = 1;
  std::vector<Vec3> r;
  for (int k = 0; k < 2; ++k)
    for (int j = 0; j < 2; ++j)
      for (int i = 0; i < 3; ++i) r.push_back(Vec3(i - 1.0, j - 0.5, k - 0.5));
  const Real k = elementStiffness(m, 3, h, 2, 2, r.data(), r.size());
  const Real V = 2;
  Mat3 along = Mat3::Zero(), across = Mat3::Zero();
  along(0, 0) = 0.01, across(1, 1) = 0.01;
  const Real continuum = 0.5 * m.youngsModulus * 1e-4 * V;
  EXPECT_NEAR(elementEnergy(k, r, along), continuum, 1e-9 * continuum);
  EXPECT_NEAR(elementEnergy(k, r, across) / continuum, 3.0 / 8.0, 1e-12);
}

// Paper scaling: k_e = k / s_e (coarse elements softer per metre), one voxel's mass per vertex.
TEST(Material, PaperRules) {
  MaterialSettings m;
  m.scaling = Scaling::Paper;
  m.paperK = 500;
  m.density = 800;
  const auto r = boxCorners(Vec3(1, 1, 1), 3);
  EXPECT_DOUBLE_EQ(elementStiffness(m, 3, 0.5, 8, 1.0, r.data(), r.size()), 500);
  EXPECT_DOUBLE_EQ(elementStiffness(m, 3, 0.5, 64, 2.0, r.data(), r.size()), 250);
  EXPECT_DOUBLE_EQ(paperVertexMass(m, 0.5), 100);
}

// Consistent masses: a cell's corners together carry its whole mass, in 2D a slab one voxel thick.
TEST(Material, CellMassSplitsOverCorners) {
  MaterialSettings m;
  m.density = 1200;
  const Real h = 0.02;
  for (int edge : {1, 2, 8}) {
    EXPECT_NEAR(8 * cellCornerMass(m, h, edge, 3), m.density * std::pow(edge * h, 3), 1e-15);
    EXPECT_NEAR(4 * cellCornerMass(m, h, edge, 2), m.density * std::pow(edge * h, 2) * h, 1e-15);
  }
}

TEST(Material, SpringPeriod) {
  EXPECT_NEAR(springPeriod(1.0, 4 * std::numbers::pi * std::numbers::pi), 1.0, 1e-15);
  EXPECT_NEAR(springPeriod(4.0, 1.0), 4 * std::numbers::pi, 1e-14);
  const auto r = boxCorners(Vec3(1, 2, 3), 3);
  const Mat3 S = restSecondMoment(r.data(), r.size());
  EXPECT_NEAR(S(0, 0), 8 * 0.25, 1e-15);
  EXPECT_NEAR(S(1, 1), 8 * 1.0, 1e-15);
  EXPECT_NEAR(S(2, 2), 8 * 2.25, 1e-14);
  EXPECT_NEAR(S(0, 1), 0, 1e-15);
}
