// Display surfaces (surface.h, paper sec. 3.3): closed, outward, over simulated vertices only.
#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "gradel/isosurface.h"
#include "gradel/surface.h"
#include "test_support.h"

namespace gradel {
namespace {

struct Case {
  std::string name;
  VoxelVolume volume;
};

// A 10^3 box with a 4-voxel-deep notch cut into one face: concave steps on three axes.
VoxelVolume notchedBox() {
  VoxelVolume v = rasterize(presetShape("box", 10, 3));
  for (int k = 3; k < 7; ++k)
    for (int j = 6; j < 10; ++j)
      for (int i = 2; i < 5; ++i) v.set(i, j, k, false);
  return v;
}

std::vector<Case> cases3D() {
  return {{"box", rasterize(presetShape("box", 6, 3))},
          {"sphere", rasterize(presetShape("sphere", 12, 3))},
          {"sphere_odd", rasterize(presetShape("sphere", 9, 3))},
          {"cylinder", rasterize(presetShape("cylinder", 10, 3))},
          {"notch", notchedBox()}};
}

std::vector<Vec3> restLattice(const Layout& layout, const DisplaySurface& s) {
  std::vector<Vec3> x(s.modelVertex.size());
  for (size_t i = 0; i < x.size(); ++i) x[i] = layout.vertices[s.modelVertex[i]].cast<Real>();
  return x;
}

// Six times the signed volume enclosed (divergence theorem), in lattice units.
Real signedVolume(const std::vector<Vec3>& x, const DisplaySurface& s) {
  Real v6 = 0;
  for (const auto& t : s.triangles) v6 += x[t[0]].dot(x[t[1]].cross(x[t[2]]));
  return v6 / 6;
}

void expectClosedAndOriented(const DisplaySurface& s, const std::string& what) {
  std::map<std::pair<uint32_t, uint32_t>, int> directed;
  for (const auto& t : s.triangles)
    for (int k = 0; k < 3; ++k) ++directed[{t[k], t[(k + 1) % 3]}];
  size_t bad = 0;
  for (const auto& [e, n] : directed) {
    auto rev = directed.find({e.second, e.first});
    if (rev == directed.end() || rev->second != n) ++bad;
  }
  EXPECT_EQ(bad, 0u) << what << ": every directed edge must be matched by exactly one reverse edge";
}

TEST(DisplaySurface, VoxelAndSmoothSurfacesAreClosedOutwardAndUseSimulatedVerticesOnly) {
  for (const Case& c : cases3D())
    for (LayoutKind kind : {LayoutKind::Gradational, LayoutKind::Uniform, LayoutKind::Voxel})
      for (SurfaceKind sk : {SurfaceKind::Voxel, SurfaceKind::Smooth}) {
        const std::string what = c.name + "/" + layoutKindName(kind) + "/" + surfaceKindName(sk);
        const Layout layout = buildLayout(c.volume, kind);
        const DisplaySurface s = buildDisplaySurface(layout, c.volume, sk);
        ASSERT_FALSE(s.triangles.empty()) << what;
        for (uint32_t m : s.modelVertex) ASSERT_LT(m, layout.numVertices()) << what;
        for (const auto& t : s.triangles)
          for (uint32_t v : t) ASSERT_LT(v, s.modelVertex.size()) << what;
        expectClosedAndOriented(s, what);

        const std::vector<Vec3> x = restLattice(layout, s);
        size_t degenerate = 0;
        for (const auto& t : s.triangles)
          if ((x[t[1]] - x[t[0]]).cross(x[t[2]] - x[t[0]]).norm() < 1e-9) ++degenerate;
        EXPECT_EQ(degenerate, 0u) << what;

        // Outward normals: the enclosed volume is positive. The staircase encloses exactly the
        // voxels; faces laid over concave steps only add volume.
        const Real vol = signedVolume(x, s), voxels = Real(c.volume.countFilled());
        if (sk == SurfaceKind::Voxel)
          EXPECT_NEAR(vol, voxels, 1e-9) << what;
        else
          EXPECT_GE(vol, voxels - 1e-9) << what;
      }
}

TEST(DisplaySurface, SmoothSurfaceCoversConcaveSteps) {
  // The sphere's staircase has concave steps; the smooth surface must lay faces over them
  // (more enclosed volume, different triangles) while the box has none to cover.
  const VoxelVolume sphere = rasterize(presetShape("sphere", 12, 3));
  const Layout ls = buildLayout(sphere, LayoutKind::Gradational);
  const DisplaySurface vs = buildDisplaySurface(ls, sphere, SurfaceKind::Voxel);
  const DisplaySurface ss = buildDisplaySurface(ls, sphere, SurfaceKind::Smooth);
  EXPECT_GT(signedVolume(restLattice(ls, ss), ss), signedVolume(restLattice(ls, vs), vs) + 10);

  const VoxelVolume box = rasterize(presetShape("box", 8, 3));
  const Layout lb = buildLayout(box, LayoutKind::Gradational);
  EXPECT_EQ(buildDisplaySurface(lb, box, SurfaceKind::Smooth).triangles,
            buildDisplaySurface(lb, box, SurfaceKind::Voxel).triangles);
}

TEST(DisplaySurface, TwoDimensionalSurfaceTilesTheRegionFacingPlusZ) {
  for (const std::string shape : {"box", "sphere"}) {
    const VoxelVolume v = rasterize(presetShape(shape, 12, 2));
    const Layout layout = buildLayout(v, LayoutKind::Gradational);
    for (SurfaceKind sk : {SurfaceKind::Voxel, SurfaceKind::Smooth}) {
      const DisplaySurface s = buildDisplaySurface(layout, v, sk);
      const std::vector<Vec3> x = restLattice(layout, s);
      Real area = 0;
      for (const auto& t : s.triangles) {
        const Real a2 = (x[t[1]] - x[t[0]]).cross(x[t[2]] - x[t[0]]).z();
        EXPECT_GT(a2, 0) << shape << ": every triangle faces +z";
        area += a2 / 2;
      }
      if (sk == SurfaceKind::Voxel)
        EXPECT_NEAR(area, Real(v.countFilled()), 1e-9) << shape;
      else
        EXPECT_GE(area, Real(v.countFilled())) << shape;
    }
  }
}

TEST(DisplaySurface, SurfaceMeshMovesWithTheModelVertices) {
  const test::Body b = test::makeBody("sphere", 8, 3, LayoutKind::Gradational);
  const DisplaySurface s = buildDisplaySurface(b.layout, b.volume, SurfaceKind::Smooth);
  std::vector<Vec3> x = b.model->restPositions;
  const Vec3 shift(0.3, -0.1, 0.2);
  for (Vec3& p : x) p += shift;
  const TriangleMesh rest = surfaceMesh(s, b.model->restPositions), moved = surfaceMesh(s, x);
  ASSERT_EQ(rest.vertices.size(), moved.vertices.size());
  for (size_t i = 0; i < rest.vertices.size(); ++i) {
    EXPECT_LT((moved.vertices[i] - rest.vertices[i] - shift).norm(), 1e-12);
    EXPECT_NEAR(moved.normals[i].norm(), 1.0, 1e-12);
    EXPECT_NEAR(moved.normals[i].dot(rest.normals[i]), 1.0, 1e-12);
  }
  // Normals never point into the sphere (at the rim of a flat step they may be tangential).
  Vec3 c = Vec3::Zero();
  for (const Vec3& p : rest.vertices) c += p;
  c /= Real(rest.vertices.size());
  for (size_t i = 0; i < rest.vertices.size(); ++i)
    EXPECT_GT(rest.normals[i].dot((rest.vertices[i] - c).normalized()), -1e-9);
}

TEST(DisplaySurface, ParseSurfaceKindRejectsUnknownNames) {
  EXPECT_EQ(parseSurfaceKind("smooth"), SurfaceKind::Smooth);
  EXPECT_THROW(parseSurfaceKind("marching"), InputError);
}

}  // namespace
}  // namespace gradel

namespace gradel {
namespace {

TEST(Isosurface, ClosedOutwardAndCloseToTheVoxelVolume) {
  for (const Case& c : cases3D()) {
    const TriangleMesh m = isosurface(c.volume, Vec3(0.1, 0.2, 0.3));
    ASSERT_FALSE(m.triangles.empty()) << c.name;
    DisplaySurface s;
    s.triangles = m.triangles;
    expectClosedAndOriented(s, "isosurface " + c.name);
    Real v6 = 0;
    for (const auto& t : m.triangles) v6 += m.vertices[t[0]].dot(m.vertices[t[1]].cross(m.vertices[t[2]]));
    const Real h3 = std::pow(c.volume.voxelSize(), 3), voxels = Real(c.volume.countFilled()) * h3;
    // Rounded edges and corners: somewhat less than the voxels, never inside out.
    EXPECT_GT(v6 / 6, 0.6 * voxels) << c.name;
    EXPECT_LT(v6 / 6, 1.05 * voxels) << c.name;
  }
  EXPECT_THROW(isosurface(rasterize(presetShape("box", 4, 2)), Vec3::Zero()), InputError);
}

// The viewer's coarse display mesh (render/display_budget.h): sampled every `step` voxels the
// isosurface stays closed and outward, encloses about the same volume, and has about step^2
// times fewer triangles; step 1 is the full surface, bit for bit.
TEST(Isosurface, CoarserStepHasStepSquaredFewerTrianglesAroundTheSameVolume) {
  const VoxelVolume volume = rasterize(presetShape("sphere", 32, 3));
  const Vec3 origin(0.1, 0.2, 0.3);
  const TriangleMesh full = isosurface(volume, origin);
  const TriangleMesh one = isosurface(volume, origin, 1);
  EXPECT_EQ(one.triangles, full.triangles);
  EXPECT_EQ(one.vertices, full.vertices);
  const Real voxels = Real(volume.countFilled()) * std::pow(volume.voxelSize(), 3);
  for (int step : {2, 3, 4}) {
    const TriangleMesh m = isosurface(volume, origin, step);
    ASSERT_FALSE(m.triangles.empty()) << step;
    DisplaySurface s;
    s.triangles = m.triangles;
    expectClosedAndOriented(s, "isosurface step " + std::to_string(step));
    EXPECT_LT(double(m.triangles.size()), 1.2 * double(full.triangles.size()) / (step * step)) << step;
    EXPECT_GT(double(m.triangles.size()), 0.6 * double(full.triangles.size()) / (step * step)) << step;
    Real v6 = 0;
    for (const auto& t : m.triangles) v6 += m.vertices[t[0]].dot(m.vertices[t[1]].cross(m.vertices[t[2]]));
    EXPECT_GT(v6 / 6, 0.8 * voxels) << step;
    EXPECT_LT(v6 / 6, 1.1 * voxels) << step;
  }
  EXPECT_THROW(isosurface(volume, origin, 0), InputError);
}

}  // namespace
}  // namespace gradel

#include "gradel/display_normals.h"

namespace gradel {
namespace {

// Mean angle [degrees] between each normal and the direction from `centre` to its point.
double meanAngleDegrees(const std::vector<Vec3>& points, const std::vector<Vec3>& normals, const Vec3& centre) {
  double sum = 0;
  for (size_t i = 0; i < points.size(); ++i) {
    const Real c = std::clamp(normals[i].normalized().dot((points[i] - centre).normalized()), -1.0, 1.0);
    sum += std::acos(c) * 180 / M_PI;
  }
  return sum / double(points.size());
}

Vec3 voxelCentroid(const VoxelVolume& v) {  // lattice coordinates
  Vec3 c = Vec3::Zero();
  size_t n = 0;
  for (int k = 0; k < v.nz(); ++k)
    for (int j = 0; j < v.ny(); ++j)
      for (int i = 0; i < v.nx(); ++i)
        if (v.at(i, j, k)) c += Vec3(i + 0.5, j + 0.5, k + 0.5), ++n;
  return c / Real(n);
}

// Issue 28: a sphere at rest looks like a sphere at every size, in the smooth surface and the
// embedded isosurface: the drawn normals' mean angle to the analytic sphere's (from its centre),
// against the mesh's own (face-averaged) normals, the display before the field normals. The
// table is docs/viewer.md's.
TEST(DisplayNormals, SphereNormalsMatchTheAnalyticSphereAtEverySize) {
  std::printf("size  smooth: own  drawn   isosurface: own  drawn  [mean angle error, degrees]\n");
  for (int n : {12, 32, 64, 128}) {
    const VoxelVolume volume = rasterize(presetShape("sphere", n, 3, 1.0));
    const Vec3 centre = voxelCentroid(volume);
    const Layout layout = buildLayout(volume, LayoutKind::Gradational);
    const DisplaySurface s = buildDisplaySurface(layout, volume, SurfaceKind::Smooth);
    const std::vector<Vec3> rest = restLattice(layout, s);
    std::vector<Vec3> positions(layout.vertices.size());
    for (size_t i = 0; i < positions.size(); ++i) positions[i] = layout.vertices[i].cast<Real>();
    const TriangleMesh drawn = surfaceMesh(s, positions);
    const double smoothOwn = meanAngleDegrees(rest, smoothVertexNormals(rest, s.triangles), centre);
    const double smoothDrawn = meanAngleDegrees(drawn.vertices, drawn.normals, centre);
    const TriangleMesh iso = isosurface(volume, Vec3::Zero());
    const double isoOwn = meanAngleDegrees(iso.vertices, vertexNormals(iso.vertices, iso.triangles), centre);
    const double isoDrawn = meanAngleDegrees(iso.vertices, iso.normals, centre);
    std::printf("%4d  %10.2f %6.2f  %15.2f %6.2f\n", n, smoothOwn, smoothDrawn, isoOwn, isoDrawn);
    EXPECT_LT(smoothDrawn, 0.5 * smoothOwn) << n;
    EXPECT_LT(isoDrawn, 0.5 * isoOwn) << n;
    EXPECT_LT(smoothDrawn, 2.0) << n;
    EXPECT_LT(isoDrawn, 2.0) << n;
  }
}

// The drawn normals move with the body: exactly the rest field normals at rest and after a
// translation; after a rotation they follow it up to the twist about each normal that the
// smallest rotation leaves out (display_normals.h): 4 degrees on average at size 10.
TEST(DisplayNormals, CarriedNormalsFollowAMovedBody) {
  const test::Body b = test::makeBody("sphere", 10, 3, LayoutKind::Gradational);
  const DisplaySurface s = buildDisplaySurface(b.layout, b.volume, SurfaceKind::Smooth);
  ASSERT_EQ(s.restFieldNormals.size(), s.modelVertex.size());
  const Mat3 R = Eigen::AngleAxis<Real>(0.9, Vec3(1, 2, 3).normalized()).toRotationMatrix();
  std::vector<Vec3> shifted = b.model->restPositions, turned = shifted;
  for (Vec3& p : shifted) p += Vec3(0.1, 0.2, 0.3);
  for (Vec3& p : turned) p = R * p;
  const TriangleMesh rest = surfaceMesh(s, b.model->restPositions), moved = surfaceMesh(s, shifted),
                     rotated = surfaceMesh(s, turned);
  double sum = 0, worst = 0;
  for (size_t i = 0; i < rest.normals.size(); ++i) {
    EXPECT_LT((rest.normals[i] - s.restFieldNormals[i]).norm(), 1e-9);
    EXPECT_LT((moved.normals[i] - rest.normals[i]).norm(), 1e-9);
    const double angle = std::acos(std::clamp(rotated.normals[i].dot(R * rest.normals[i]), -1.0, 1.0)) * 180 / M_PI;
    sum += angle, worst = std::max(worst, angle);
  }
  const double mean = sum / double(rest.normals.size());
  std::printf("rotated by 0.9 rad: drawn normals vs the rotated rest ones: mean %.2f, max %.2f degrees\n", mean, worst);
  EXPECT_LT(mean, 6.0);    // 4.2 measured; the mesh's own normals are 8.4 degrees off the sphere
  EXPECT_LT(worst, 25.0);  // 19.7 measured
}

}  // namespace
}  // namespace gradel
