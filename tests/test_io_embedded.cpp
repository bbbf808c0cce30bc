// A body voxelised from a mesh file carries that mesh as its embedded render mesh (scene.h,
// embedding.h): the user's own vertices and triangles, placed exactly where they were voxelised,
// following the elements; `gradel render --export` writes it. Vertices outside every element
// bind to the element nearest to them.
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "gradel/embedding.h"
#include "gradel/io/byte_stream.h"
#include "gradel/io/mesh_file.h"
#include "gradel/scene.h"
#include "test_support.h"

namespace gradel {
namespace {

namespace fs = std::filesystem;

std::string source(const std::string& rel) { return std::string(GRADEL_SOURCE_DIR) + "/" + rel; }

TriangleMesh readSampleObj() {
  auto in = io::openFileStream(source("samples/torus.obj"));
  return io::readObj(*in, io::ReadLimits{});
}

TEST(SourceMesh, TorusObjSceneEmbedsTheFileMeshWhereItWasVoxelised) {
  const Scene scene = loadScene(source("scenes/torus-obj.json"));
  const BuiltScene b = buildScene(scene);
  const TriangleMesh file = readSampleObj();
  ASSERT_TRUE(b.bodies[0].sourceMesh && b.bodies[0].embedded);
  ASSERT_EQ(b.bodies[0].sourceMesh->vertices.size(), file.vertices.size());
  EXPECT_EQ(b.bodies[0].embedded->weightStart.size(), file.vertices.size() + 1);
  EXPECT_EQ(b.bodies[0].embedded->triangles, file.triangles);

  // A similarity of the file mesh: scaled so its longest edge spans `resolution` voxels.
  Vec3 lo = file.vertices[0], hi = lo;
  for (const Vec3& p : file.vertices) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  const Real scale = 24 * 0.01 / (hi - lo).maxCoeff();  // torus-obj.json: resolution 24, voxel_size 0.01
  for (size_t v = 0; v < file.vertices.size(); ++v) {
    const Vec3 expected = scale * (file.vertices[v] - file.vertices[0]);
    EXPECT_LT((b.bodies[0].sourceMesh->vertices[v] - b.bodies[0].sourceMesh->vertices[0] - expected).norm(), 1e-12) << v;
  }
  // ... lying on the body: its bounding box matches the model's within a voxel.
  Vec3 mlo = b.bodies[0].model->restPositions[0], mhi = mlo, slo = b.bodies[0].sourceMesh->vertices[0], shi = slo;
  for (const Vec3& p : b.bodies[0].model->restPositions) mlo = mlo.cwiseMin(p), mhi = mhi.cwiseMax(p);
  for (const Vec3& p : b.bodies[0].sourceMesh->vertices) slo = slo.cwiseMin(p), shi = shi.cwiseMax(p);
  EXPECT_LT((slo - mlo).cwiseAbs().maxCoeff(), 0.01);
  EXPECT_LT((shi - mhi).cwiseAbs().maxCoeff(), 0.01);

  // At t = 0 the embedded mesh is the rest mesh.
  const TriangleMesh atStart = embeddedMesh(*b.bodies[0].embedded, b.world->state().positions);
  ASSERT_EQ(atStart.vertices.size(), file.vertices.size());
  for (size_t v = 0; v < atStart.vertices.size(); ++v)
    EXPECT_LT((atStart.vertices[v] - b.bodies[0].sourceMesh->vertices[v]).norm(), 1e-12) << v;

  // A rigid motion of the model moves the mesh by the same motion, exactly.
  const Mat3 R = Eigen::AngleAxisd(1.1, Vec3(0.3, -1, 0.5).normalized()).toRotationMatrix();
  const Vec3 t(0.2, 0.05, -0.4);
  std::vector<Vec3> x = b.world->state().positions;
  for (Vec3& p : x) p = R * p + t;
  const TriangleMesh moved = embeddedMesh(*b.bodies[0].embedded, x);
  for (size_t v = 0; v < moved.vertices.size(); ++v)
    EXPECT_LT((moved.vertices[v] - (R * b.bodies[0].sourceMesh->vertices[v] + t)).norm(), 1e-10) << v;
}

TEST(SourceMesh, OnlyMeshSourcesHaveOne) {
  for (const char* name : {"scenes/torus-binvox.json", "scenes/ct-nrrd.json", "scenes/drop.json"}) {
    const BuiltScene b = buildScene(loadScene(source(name)));
    EXPECT_FALSE(b.bodies[0].sourceMesh) << name;
    EXPECT_FALSE(b.bodies[0].embedded) << name;
  }
  for (const char* name : {"scenes/torus-stl.json", "scenes/pawn-ply.json"}) {
    const BuiltScene b = buildScene(loadScene(source(name)));
    ASSERT_TRUE(b.bodies[0].embedded) << name;
    const TriangleMesh m = embeddedMesh(*b.bodies[0].embedded, b.world->state().positions);
    for (size_t v = 0; v < m.vertices.size(); ++v) ASSERT_LT((m.vertices[v] - b.bodies[0].sourceMesh->vertices[v]).norm(), 1e-12);
  }
}

// The region (filled voxels) of every element, as in embedding.cpp but written out here.
std::vector<int32_t> owners(const Layout& layout) {
  const auto& n = layout.dims;
  std::vector<int32_t> owner(size_t(n[0]) * n[1] * n[2], -1);
  for (size_t e = 0; e < layout.numElements(); ++e) {
    const int32_t c = layout.cellSize[e];
    for (int k = 0; k < 8; ++k)
      if (layout.cellMask[e] >> k & 1) {
        const Int3 lo = layout.origin[e] + c * Int3(k & 1, k >> 1 & 1, k >> 2 & 1);
        for (int32_t z = lo.z(); z < lo.z() + c; ++z)
          for (int32_t y = lo.y(); y < lo.y() + c; ++y)
            for (int32_t x = lo.x(); x < lo.x() + c; ++x)
              if (x < n[0] && y < n[1] && z < n[2])
                owner[size_t(x) + n[0] * (size_t(y) + n[1] * size_t(z))] = int32_t(e);
      }
  }
  return owner;
}

TEST(SourceMesh, VerticesOutsideTheBodyBindToTheNearestElement) {
  const test::Body b = test::makeBody("sphere", 12, 3, LayoutKind::Gradational);
  const Real h = b.model->voxelSize;
  const Vec3 origin = b.model->restPositions[0] - b.layout.vertices[0].cast<Real>() * h;
  // Points just outside, a few voxels out, far out (past the shell search), inside the grid's
  // empty corner and beyond the grid on every side.
  const std::vector<Vec3> lattice = {{6, 6, 12.3}, {6.2, -0.4, 6.1}, {-3, 6.5, 6.5},  {0.2, 0.3, 0.1}, {30, 2, 6},
                                     {6, 6, -40},  {-25, -25, -25},  {12.9, 12.9, 6}, {6.4, 100, 6.6}};
  TriangleMesh mesh;
  for (const Vec3& q : lattice) mesh.vertices.push_back(origin + h * q);
  mesh.triangles = {{0, 1, 2}, {3, 4, 5}, {6, 7, 8}};
  const EmbeddedMesh e = embedMesh(mesh, b.layout, *b.model);
  const std::vector<int32_t> owner = owners(b.layout);
  const auto& n = b.layout.dims;
  for (size_t v = 0; v < lattice.size(); ++v) {
    // Brute force: the distance from the point to each element's region.
    Real best = 1e300;
    std::vector<Real> dist(b.layout.numElements(), 1e300);
    for (int k = 0; k < n[2]; ++k)
      for (int j = 0; j < n[1]; ++j)
        for (int i = 0; i < n[0]; ++i) {
          const int32_t o = owner[size_t(i) + n[0] * (size_t(j) + n[1] * size_t(k))];
          if (o < 0) continue;
          const Vec3 c = lattice[v].cwiseMax(Vec3(i, j, k)).cwiseMin(Vec3(i + 1, j + 1, k + 1));
          const Real d = (c - lattice[v]).norm();
          dist[size_t(o)] = std::min(dist[size_t(o)], d);
          best = std::min(best, d);
        }
    EXPECT_GT(best, 0) << "point " << v << " should lie outside the body";
    EXPECT_LE(dist[e.element[v]], best + 1e-9) << "point " << v << " bound to element " << e.element[v];
  }
  // And they still move rigidly with the body.
  const Mat3 R = Eigen::AngleAxisd(-0.6, Vec3(1, 1, 0).normalized()).toRotationMatrix();
  std::vector<Vec3> x = b.model->restPositions;
  for (Vec3& p : x) p = R * p;
  const TriangleMesh moved = embeddedMesh(e, x);
  for (size_t v = 0; v < lattice.size(); ++v) EXPECT_LT((moved.vertices[v] - R * mesh.vertices[v]).norm(), 1e-9);
}

int run(const std::string& cmd) {
  const int status = std::system(cmd.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

size_t countLines(const std::string& text, const std::string& prefix) {
  std::istringstream in(text);
  size_t n = 0;
  for (std::string line; std::getline(in, line);) n += line.rfind(prefix, 0) == 0;
  return n;
}

TEST(SourceMesh, CliRenderExportWritesTheUsersMesh) {
#ifndef GRADEL_WITH_RENDER
  GTEST_SKIP() << "`gradel render` is not built (GRADEL_BUILD_RENDER=OFF)";
#endif
  const fs::path dir = fs::temp_directory_path() / ("gradel-embedded-cli-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  const TriangleMesh file = readSampleObj();
  const std::string cli = std::string("'") + GRADEL_CLI_PATH + "' render '" + source("scenes/torus-obj.json") +
                          "' --no-pictures --frames 3 --export obj";
  // Default surface for a body from a mesh file: the embedded file mesh.
  ASSERT_EQ(run(cli + " --out '" + (dir / "auto").string() + "' > /dev/null 2>&1"), 0);
  ASSERT_EQ(run(cli + " --surface embedded --out '" + (dir / "embedded").string() + "' > /dev/null 2>&1"), 0);
  ASSERT_EQ(run(cli + " --surface smooth --out '" + (dir / "smooth").string() + "' > /dev/null 2>&1"), 0);
  for (const char* which : {"auto", "embedded"})
    for (const char* frame : {"surface_00000.obj", "surface_00002.obj"}) {
      const std::string obj = slurp(dir / which / frame);
      EXPECT_EQ(countLines(obj, "v "), file.vertices.size()) << which << " " << frame;
      EXPECT_EQ(countLines(obj, "f "), file.triangles.size()) << which << " " << frame;
    }
  // The frames differ (the torus falls), the smooth display surface is another mesh.
  EXPECT_NE(slurp(dir / "auto" / "surface_00000.obj"), slurp(dir / "auto" / "surface_00002.obj"));
  EXPECT_NE(countLines(slurp(dir / "smooth" / "surface_00000.obj"), "v "), file.vertices.size());
  fs::remove_all(dir);
}

}  // namespace
}  // namespace gradel
