// Embedded render meshes (embedding.h): carried exactly by rigid and affine motion.
#include <gtest/gtest.h>

#include "gradel/embedding.h"
#include "gradel/surface.h"
#include "test_support.h"

namespace gradel {
namespace {

// A mesh inside and slightly outside the body: the smooth display surface pushed out by 0.3
// voxel along its normals, plus its triangles.
TriangleMesh testMesh(const test::Body& b) {
  const DisplaySurface s = buildDisplaySurface(b.layout, b.volume, SurfaceKind::Smooth);
  TriangleMesh m = surfaceMesh(s, b.model->restPositions);
  for (size_t i = 0; i < m.vertices.size(); ++i) m.vertices[i] += 0.3 * b.model->voxelSize * m.normals[i];
  m.normals.clear();
  return m;
}

TEST(EmbeddedMesh, WeightsSumToOneAndRestPositionsAreReproduced) {
  const test::Body b = test::makeBody("sphere", 10, 3, LayoutKind::Gradational);
  const TriangleMesh rest = testMesh(b);
  const EmbeddedMesh e = embedMesh(rest, b.layout, *b.model);
  ASSERT_EQ(e.weightStart.size(), rest.vertices.size() + 1);
  for (size_t v = 0; v < rest.vertices.size(); ++v) {
    Real sum = 0;
    for (uint32_t k = e.weightStart[v]; k < e.weightStart[v + 1]; ++k) sum += e.weight[k];
    EXPECT_NEAR(sum, 1.0, 1e-12);
  }
  const TriangleMesh atRest = embeddedMesh(e, b.model->restPositions);
  for (size_t v = 0; v < rest.vertices.size(); ++v) EXPECT_LT((atRest.vertices[v] - rest.vertices[v]).norm(), 1e-12);
}

TEST(EmbeddedMesh, FollowsRigidAndAffineMotionExactly) {
  for (int dim : {2, 3}) {
    const test::Body b = test::makeBody("sphere", 10, dim, LayoutKind::Gradational);
    TriangleMesh rest = testMesh(b);
    if (dim == 2) {  // a flat mesh for a flat body
      for (Vec3& p : rest.vertices) p.z() = 0;
    }
    const EmbeddedMesh e = embedMesh(rest, b.layout, *b.model);
    Mat3 A = Eigen::AngleAxisd(0.7, dim == 3 ? Vec3(1, 2, 3).normalized() : Vec3(0, 0, 1)).toRotationMatrix();
    A(0, 0) *= 1.2;  // and a stretch
    const Vec3 t(0.1, -0.2, dim == 3 ? 0.05 : 0.0);
    std::vector<Vec3> x = b.model->restPositions;
    for (Vec3& p : x) p = A * p + t;
    const TriangleMesh moved = embeddedMesh(e, x);
    for (size_t v = 0; v < rest.vertices.size(); ++v)
      EXPECT_LT((moved.vertices[v] - (A * rest.vertices[v] + t)).norm(), 1e-10) << "dim " << dim << " vertex " << v;
  }
}

TEST(EmbeddedMesh, RejectsBadMeshes) {
  const test::Body b = test::makeBody("box", 4, 3, LayoutKind::Gradational);
  TriangleMesh m;
  EXPECT_THROW(embedMesh(m, b.layout, *b.model), InputError);
  m.vertices = {Vec3(0.01, 0.01, 0.01), Vec3(0.02, 0.01, 0.01), Vec3(0.01, 0.02, 0.01)};
  m.triangles = {{0, 1, 3}};
  EXPECT_THROW(embedMesh(m, b.layout, *b.model), InputError);
  m.triangles = {{0, 1, 2}};
  m.vertices[1].x() = std::nan("");
  EXPECT_THROW(embedMesh(m, b.layout, *b.model), InputError);
}

}  // namespace
}  // namespace gradel
