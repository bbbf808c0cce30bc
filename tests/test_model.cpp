// model: the rest model built from a layout (masses, stiffness).
#include <gtest/gtest.h>

#include <set>

#include "gradel/element.h"
#include "gradel/shared/validation.h"
#include "test_support.h"

using namespace gradel;
using namespace gradel::test;

TEST(Model, ConsistentIncompleteElementsExactAlongTheirLongAxisNeverStifferAcross) {
  // The interior of a gradational bar 8 voxels across is made of incomplete level-1 elements
  // whose two filled cells form a line along x (fig. 6). Under a uniform strain along x each
  // stores exactly the continuum energy E/2 eps^2 V_e; across (y, z) 3/8 of it (material.h).
  BarSpec bar;
  bar.across = 8;
  bar.along = 16;
  bar.layout = LayoutKind::Gradational;
  bar.material.youngsModulus = 1e7;
  BuiltScene b = buildScene(barScene(bar, SimulationSettings{}, false));
  const RestModel& m = *b.bodies[0].model;
  const std::vector<Vec3> R0s = m.pairRestOffsets();
  const Real h = bar.voxelSize(), eps = 1e-4;
  int incomplete = 0;
  for (size_t e = 0; e < m.numElements(); ++e) {
    const uint32_t s = m.elemStart[e], n = m.elemStart[e + 1] - s;
    const Real continuum = 0.5 * 1e7 * eps * eps * Real(b.bodies[0].layout.regionVoxels(e)) * h * h * h;
    Real energy[3];
    for (int a = 0; a < 3; ++a) {
      std::vector<Vec3> x = m.restPositions;
      for (Vec3& p : x) p[a] *= 1 + eps;
      std::vector<Vec3> f(n);
      Quat q = Quat::Identity();
      energy[a] =
          elementForces(3, x.data(), &m.elemVerts[s], &R0s[s], int(n), m.stiffness[e], q, f.data(), 50)
              .energy;
      EXPECT_LE(energy[a], continuum * (1 + 1e-6)) << "element " << e << " axis " << a;
    }
    const int cells = __builtin_popcount(b.bodies[0].layout.cellMask[e]);
    if (b.bodies[0].layout.isFull(e) || cells == 1) {  // a cube: exact for every strain
      for (int a = 0; a < 3; ++a) EXPECT_NEAR(energy[a] / continuum, 1.0, 1e-6);
    } else {
      const int mask = b.bodies[0].layout.cellMask[e];
      ASSERT_TRUE(mask == 3 || mask == 12 || mask == 48 || mask == 192)
          << "expected two cells along x, got mask " << mask;
      ++incomplete;
      EXPECT_NEAR(energy[0] / continuum, 1.0, 1e-6);
      EXPECT_NEAR(energy[1] / continuum, 0.375, 1e-6);
      EXPECT_NEAR(energy[2] / continuum, 0.375, 1e-6);
    }
  }
  EXPECT_GT(incomplete, 0);
}

TEST(Model, ConsistentCubeStiffnessIsHalfEdgeTimesModulus) {
  // A full cube element of edge s with 8 corners: sum |R0|^2 = 6 s^2, V = s^3, so
  // k_e = 3 E s^3 / (6 s^2) = E s / 2 (material.h).
  MaterialSettings mat;
  mat.youngsModulus = 2.0e5;
  Body b = makeBody("box", 2, 3, LayoutKind::Gradational, mat, 0.01);
  ASSERT_EQ(b.model->numElements(), 1u);
  EXPECT_NEAR(b.model->stiffness[0], 2.0e5 * 0.02 / 2, 1e-9);
  // Each corner gets an eighth of the block's mass.
  for (Real mass : b.model->mass) EXPECT_NEAR(mass, 1000.0 * 8e-6 / 8, 1e-15);
}

TEST(Model, PaperScalingGivesEveryVertexOneVoxelsMass) {
  MaterialSettings mat;
  mat.scaling = Scaling::Paper;
  mat.density = 1.0;
  mat.paperK = 10000;
  Body b = makeBody("sphere", 12, 3, LayoutKind::Gradational, mat, 1.0);
  for (Real mass : b.model->mass) EXPECT_EQ(mass, 1.0);
  for (size_t e = 0; e < b.model->numElements(); ++e)
    EXPECT_DOUBLE_EQ(b.model->stiffness[e], 10000.0 / b.model->size[e]);  // k / s_e (sec. 2.2)
}

TEST(Model, RestOffsetsAreCentred) {
  Body b = makeBody("sphere", 10, 3, LayoutKind::Gradational);
  const RestModel& m = *b.model;
  for (size_t e = 0; e < m.numElements(); ++e) {
    Vec3 s = Vec3::Zero();
    for (uint32_t p = m.elemStart[e]; p < m.elemStart[e + 1]; ++p) s += m.restOffset(e, p);
    EXPECT_LT(s.norm(), 1e-12 * m.size[e]);  // zero up to rounding
  }
}

// Rest-derived data born with the layout and the model: the lattice-to-vertex lookup finds every
// vertex and nothing else, and the model keeps its origin (rest = origin + lattice * h).
TEST(Model, VertexLookupAndOrigin) {
  for (int dim : {2, 3})
    for (LayoutKind kind : {LayoutKind::Gradational, LayoutKind::Voxel}) {
      const Vec3 given(0.3, -1.7, 2.9), origin(0.3, -1.7, dim == 3 ? 2.9 : 0);  // a 2D body lies in z = 0
      Body b = makeBody("sphere", 9, dim, kind, {}, 0.01, given);
      const Layout& L = b.layout;
      for (size_t i = 0; i < L.numVertices(); ++i) {
        ASSERT_EQ(L.vertexAt(L.vertices[i]), i);
        EXPECT_EQ(L.vertexAt(L.vertices[i] + Int3(0, 0, 11)), Layout::kNoVertex);  // above the grid
      }
      // The grid's corner is outside the sphere.
      EXPECT_EQ(L.vertexAt(Int3(0, 0, 0)), Layout::kNoVertex);
      EXPECT_EQ(b.model->origin, origin);
      for (size_t i = 0; i < L.numVertices(); i += 7)
        EXPECT_EQ(b.model->restPositions[i], Vec3(origin + L.vertices[i].cast<Real>() * 0.01));
    }
}
