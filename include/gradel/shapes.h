// Procedural voxel shapes: box, sphere (disk in 2D), capped cylinder, and unions of them.
//
// Primitives are given in lattice units (voxels). A voxel is filled when its centre
// (i + 0.5, j + 0.5, k + 0.5) lies inside (or on) any primitive of the union. Each primitive
// carries a region label (volume.h, default 1); where primitives overlap, the last one listed
// gives the voxel its label (paint order: a stiff inclusion is listed after the tissue around it).
#pragma once

#include <string>
#include <vector>

#include "gradel/volume.h"

namespace gradel {

enum class PrimitiveKind { Box, Sphere, Cylinder };

struct Primitive {
  PrimitiveKind kind = PrimitiveKind::Box;
  Vec3 min{0, 0, 0};     ///< Box: lower corner [voxels].
  Vec3 max{0, 0, 0};     ///< Box: upper corner [voxels].
  Vec3 center{0, 0, 0};  ///< Sphere / cylinder: centre [voxels].
  Real radius = 0;       ///< Sphere / cylinder radius [voxels].
  Real halfLength = 0;   ///< Cylinder: half the length along its axis [voxels].
  int axis = 2;          ///< Cylinder axis: 0 = x, 1 = y, 2 = z.
  uint16_t label = 1;    ///< Region label of the voxels it covers (1..65535); later primitives win.

  bool contains(const Vec3& p) const;
};

/// A union of primitives rasterised into a dims[0] x dims[1] x dims[2] grid.
struct ShapeSpec {
  int dim = 3;                          ///< 2 or 3.
  std::array<int, 3> dims{12, 12, 12};  ///< Grid size [voxels]; dims[2] == 1 in 2D.
  Real voxelSize = 0.01;                ///< [m]
  std::vector<Primitive> primitives;    ///< Union; at least one.
};

/// Rasterises the union (labelled when a primitive's label is not 1). Throws InputError for a bad spec or an empty
/// result.
VoxelVolume rasterize(const ShapeSpec& spec);

/// The CLI's presets, inscribed in a size^dim grid: "box" (the full grid), "sphere" (disk in
/// 2D), "cylinder" (3D only: axis z, radius size/2, full height). Throws InputError for an
/// unknown name or a size < 1.
ShapeSpec presetShape(const std::string& name, int size, int dim, Real voxelSize = 0.01);

/// `spec` at `size` voxels along its longest side with the same physical extent: the grid, the
/// primitives and the voxel size scaled together (in 2D the one z layer stays). A preset of size
/// n scaled to m is the preset of size m. Throws InputError for a size < 1.
ShapeSpec scaleShape(const ShapeSpec& spec, int size);

class ShapeSource : public VolumeSource {
 public:
  explicit ShapeSource(ShapeSpec spec) : spec_(std::move(spec)) {}
  VoxelVolume load() const override { return rasterize(spec_); }
  std::string describe() const override { return "procedural shape"; }

 private:
  ShapeSpec spec_;
};

}  // namespace gradel
