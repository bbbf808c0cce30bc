// scaleShape (shapes.h): a shape at another resolution with its physical extent kept (the
// viewer's size slider on a scene's own shape).
#include <gtest/gtest.h>

#include "gradel/shapes.h"
#include "gradel/volume.h"
#include <array>

using namespace gradel;

namespace {

bool sameVoxels(const VoxelVolume& a, const VoxelVolume& b) {
  if (a.nx() != b.nx() || a.ny() != b.ny() || a.nz() != b.nz()) return false;
  for (int k = 0; k < a.nz(); ++k)
    for (int j = 0; j < a.ny(); ++j)
      for (int i = 0; i < a.nx(); ++i)
        if (a.at(i, j, k) != b.at(i, j, k)) return false;
  return true;
}

}  // namespace

TEST(ScaleShape, APresetScaledIsThePresetOfThatSize) {
  for (const char* name : {"sphere", "box", "cylinder"})
    for (int to : {8, 24, 40}) {
      const ShapeSpec scaled = scaleShape(presetShape(name, 12, 3, 0.01), to);
      const ShapeSpec preset = presetShape(name, to, 3, 0.12 / to);
      EXPECT_TRUE(sameVoxels(rasterize(scaled), rasterize(preset))) << name << " 12 -> " << to;
      EXPECT_NEAR(scaled.voxelSize, preset.voxelSize, 1e-15);
    }
  // 2D: the disk and the square keep their one layer.
  for (const char* name : {"sphere", "box"}) {
    const ShapeSpec scaled = scaleShape(presetShape(name, 10, 2, 0.01), 30);
    EXPECT_EQ(scaled.dims[2], 1);
    EXPECT_TRUE(sameVoxels(rasterize(scaled), rasterize(presetShape(name, 30, 2, 0.01 / 3)))) << name;
  }
}

TEST(ScaleShape, AUnionKeepsItsExtentAndItsLabels) {
  ShapeSpec s;
  s.dims = {20, 10, 10};
  s.voxelSize = 0.005;
  Primitive slab, ball;
  slab.kind = PrimitiveKind::Box, slab.max = Vec3(20, 5, 10);
  ball.kind = PrimitiveKind::Sphere, ball.center = Vec3(10, 5, 5), ball.radius = 4, ball.label = 2;
  s.primitives = {slab, ball};
  const ShapeSpec big = scaleShape(s, 40);
  EXPECT_EQ(big.dims, (std::array<int, 3>{40, 20, 20}));
  EXPECT_NEAR(big.dims[0] * big.voxelSize, s.dims[0] * s.voxelSize, 1e-12);  // the same 0.1 m
  const VoxelVolume a = rasterize(s), b = rasterize(big);
  // Each voxel of the coarse grid is 2x2x2 of the fine one: where the coarse voxel's centre is
  // well inside a primitive, so are all eight fine centres, with the same label.
  EXPECT_EQ(a.label(10, 5, 5), 2);
  for (int dk : {0, 1})
    for (int dj : {0, 1})
      for (int di : {0, 1}) EXPECT_EQ(b.label(20 + di, 10 + dj, 10 + dk), 2);
  EXPECT_EQ(b.label(1, 1, 1), 1);
  EXPECT_THROW(scaleShape(s, 0), InputError);
}
