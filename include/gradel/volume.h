// The voxel volume: the input of every layout (paper sec. 1.3, 3.2). Binary (filled or empty),
// optionally with a region label per filled voxel (materials per region, docs/layout.md).
//
// Conventions
//   * Voxel (i, j, k) is the cube [i, i+1] x [j, j+1] x [k, k+1] in lattice units; its
//     world-space size is `voxelSize` metres on every axis.
//   * Storage index is i + nx * (j + ny * k) (x fastest).
//   * A 2D volume has nz == 1 and dim == 2; its lattice points all have z == 0.
//   * Everything outside the grid counts as empty.
//   * Surface voxel (paper sec. 3.2 step 1): a filled voxel with at least one empty *face*
//     neighbour (6 in 3D, 4 in 2D); voxels on the grid border count as having an empty neighbour
//     outside.
//   * Labels: every voxel has a label, 0 = empty, 1..65535 = the region (material) it belongs to.
//     A binary volume (hasLabels() false) stores none and every filled voxel has label 1, so
//     binary volumes cost nothing extra and behave exactly as before labels existed. Once a label
//     other than 1 is set, a 2-byte label per voxel is kept next to the fill byte; the two agree
//     (label != 0 iff filled) as long as voxels are changed through set / setLabel.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "gradel/types.h"

namespace gradel {

struct TriangleMesh;  // mesh.h

class VoxelVolume {
 public:
  VoxelVolume() = default;
  /// An empty (all-zero) volume. dim is 2 or 3; for dim 2, nz must be 1. voxelSize in metres (> 0).
  VoxelVolume(int dim, int nx, int ny, int nz, Real voxelSize);

  int dim() const { return dim_; }
  int nx() const { return n_[0]; }
  int ny() const { return n_[1]; }
  int nz() const { return n_[2]; }
  const std::array<int, 3>& dims() const { return n_; }
  Real voxelSize() const { return voxelSize_; }
  size_t size() const { return data_.size(); }

  bool inside(int i, int j, int k) const { return i >= 0 && j >= 0 && k >= 0 && i < n_[0] && j < n_[1] && k < n_[2]; }
  size_t index(int i, int j, int k) const {
    return size_t(i) + size_t(n_[0]) * (size_t(j) + size_t(n_[1]) * size_t(k));
  }
  /// Filled? Out-of-grid coordinates read as empty.
  bool at(int i, int j, int k) const { return inside(i, j, k) && data_[index(i, j, k)] != 0; }
  /// Fills or empties a voxel; a filled voxel keeps its label (label 1 when it had none).
  void set(int i, int j, int k, bool v);

  /// The voxel's label: 0 when empty or outside the grid, 1 for every filled voxel of a binary volume.
  uint16_t label(int i, int j, int k) const {
    if (!at(i, j, k)) return 0;
    return labels_.empty() ? uint16_t(1) : labels_[index(i, j, k)];
  }
  /// Sets the label (0 empties the voxel); a label other than 1 makes the volume labelled.
  void setLabel(int i, int j, int k, uint16_t label);
  /// True once the volume keeps a label per voxel (labels() is then size() long).
  bool hasLabels() const { return !labels_.empty(); }
  /// Per-voxel labels (storage order); empty for a binary volume (every filled voxel is label 1).
  const std::vector<uint16_t>& labels() const { return labels_; }
  /// Allocates the per-voxel labels (1 where filled, 0 elsewhere) if not yet there, for readers
  /// that write labels and fill bytes directly; they must keep label != 0 iff data != 0.
  std::vector<uint16_t>& enableLabels();
  /// The distinct labels of the filled voxels, ascending ({1} for a binary volume).
  std::vector<uint16_t> labelsPresent() const;

  /// Surface voxel per the face-neighbour definition above.
  bool isSurface(int i, int j, int k) const;
  size_t countFilled() const;

  const std::vector<uint8_t>& data() const { return data_; }
  std::vector<uint8_t>& data() { return data_; }

 private:
  int dim_ = 3;
  std::array<int, 3> n_{0, 0, 0};
  Real voxelSize_ = 1.0;
  std::vector<uint8_t> data_;
  std::vector<uint16_t> labels_;  // empty: binary volume, every filled voxel is label 1
};

/// Where a volume comes from: procedural shapes (shapes.h), the file readers (io/volume_file.h)
/// and in-memory arrays (io/volume_data_source.h) implement it. `describe()` names the source in error messages.
class VolumeSource {
 public:
  virtual ~VolumeSource() = default;
  virtual VoxelVolume load() const = 0;
  /// The volume and, for a source voxelised from a triangle mesh, that mesh in lattice units
  /// (io/voxelize.h) in `*latticeMesh`, the body's embedded render mesh, from one read of the
  /// file. Other sources leave `*latticeMesh` untouched (pass an empty one).
  virtual VoxelVolume loadWithMesh(TriangleMesh* /*latticeMesh*/) const { return load(); }
  virtual std::string describe() const = 0;
};

}  // namespace gradel
