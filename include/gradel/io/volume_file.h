// Volume files: one description (`VolumeFileSpec`, what a scene's "body.source" holds) and one
// entry point (`readVolumeFile` / `openVolume`) for every format gradel reads. See docs/io.md.
//
//   format   extensions           binary rule
//   binvox   .binvox              non-zero voxels
//   vox      .vox                 every voxel of model `model`
//   nrrd     .nrrd                threshold / range / non-zero (grey levels)
//   nifti    .nii, .nii.gz        threshold / range / non-zero (after scl_slope / scl_inter)
//   raw      .raw (+ dims, type)  threshold / range / non-zero
//   obj      .obj                 voxelised at `resolution` (voxelize.h)
//   stl      .stl                 voxelised
//   ply      .ply                 voxelised
// Any file may be gzip-compressed (.gz after the extension); the magic bytes decide.
#pragma once

#include <array>
#include <memory>
#include <optional>
#include <string>

#include "gradel/io/grey_levels.h"
#include "gradel/io/raw_volume.h"
#include "gradel/io/read_limits.h"
#include "gradel/mesh.h"
#include "gradel/volume.h"

namespace gradel::io {

enum class VolumeFormat { Binvox, Vox, Nrrd, Nifti, Raw, Obj, Stl, Ply };

/// "binvox", "vox", "nrrd", "nifti", "raw", "obj", "stl", "ply"; InputError otherwise.
VolumeFormat parseVolumeFormat(const std::string& name);
const char* volumeFormatName(VolumeFormat f);
/// From the file name's extension (a trailing ".gz" is looked through); InputError when unknown.
VolumeFormat volumeFormatFromPath(const std::string& path);
/// Mesh formats are voxelised; the others are voxel grids already.
bool isMeshFormat(VolumeFormat f);

struct VolumeFileSpec {
  std::string path;                    ///< File to read.
  std::optional<VolumeFormat> format;  ///< nullopt: from the extension.
  Real voxelSize = 0.01;               ///< [m] edge of one voxel of the result (file spacings are not used).
  int dim = 3;                         ///< 3, or 2 for a volume one voxel thick in z (nz == 1).
  GreyRule grey;                       ///< nrrd, nifti, raw: which values are filled.
  RawLayout raw;                       ///< raw only: dims, type, byte order, header bytes.
  int resolution = 64;                 ///< obj, stl, ply: voxels along the longest edge.
  int model = 0;                       ///< vox: which model of the file.
  ReadLimits limits;                   ///< Caps checked before allocating.
};

/// Reads, converts and checks the volume (non-empty; nz == 1 for dim 2). InputError naming the
/// file on any problem. For a mesh format, `latticeMesh` (when given) receives the mesh as it was
/// voxelised, in lattice units (voxelize.h); for the others it is cleared.
VoxelVolume readVolumeFile(const VolumeFileSpec& spec, TriangleMesh* latticeMesh = nullptr);

/// Reads a volume of known format from a stream (already decompressed); used by readVolumeFile
/// and by the fuzz targets. `dim` and emptiness are not checked here. `latticeMesh` as above.
VoxelVolume readVolumeStream(ByteStream& in, VolumeFormat format, const VolumeFileSpec& spec,
                             TriangleMesh* latticeMesh = nullptr);

/// A VolumeSource reading `spec` each time it is loaded.
class FileVolumeSource : public VolumeSource {
 public:
  explicit FileVolumeSource(VolumeFileSpec spec) : spec_(std::move(spec)) {}
  VoxelVolume load() const override { return readVolumeFile(spec_); }
  VoxelVolume loadWithMesh(TriangleMesh* latticeMesh) const override { return readVolumeFile(spec_, latticeMesh); }
  std::string describe() const override { return spec_.path; }
  const VolumeFileSpec& spec() const { return spec_; }

 private:
  VolumeFileSpec spec_;
};

std::unique_ptr<VolumeSource> openVolume(const VolumeFileSpec& spec);

}  // namespace gradel::io
