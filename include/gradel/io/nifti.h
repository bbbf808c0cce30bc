// NIfTI-1 and NIfTI-2 single-file images (.nii, and .nii.gz through io::gzipStream), the
// neuroimaging format. The header layout is Debian libnifti2-dev's nifti1.h / nifti2.h
// (nifti_1_header, 348 bytes; nifti_2_header, 540 bytes). gradel parses it itself rather than
// through nifti_image_read: the library reads the whole image into memory (a second full copy
// next to the voxel volume) and trusts header sizes, which a hostile file can make overflow.
//
//   * byte order from sizeof_hdr (348 / 540 or byte-swapped);
//   * magic "n+1" / "n+2" (data in the same file at vox_offset); two-file "ni1" pairs are refused;
//   * dim[0] in 1..7; dim[1..3] become gradel's x, y, z (i fastest, as in the file); extra
//     dimensions (time, ...) beyond 3: only the first volume is read;
//   * datatype: uint8/int8/int16/uint16/int32/uint32/int64/uint64/float32/float64; complex and
//     RGB types are refused;
//   * scl_slope / scl_inter: when slope is non-zero and finite the rule applies to
//     slope * stored + inter (e.g. Hounsfield units), as the standard says;
//   * pixdim (spacing) is not used: the scene's "voxel_size" gives the lattice.
#pragma once

#include "gradel/io/byte_stream.h"
#include "gradel/io/grey_levels.h"
#include "gradel/io/read_limits.h"
#include "gradel/volume.h"

namespace gradel::io {

/// Reads a NIfTI-1 or NIfTI-2 .nii stream (already decompressed); voxels filled by `rule`.
VoxelVolume readNifti(ByteStream& in, const GreyRule& rule, Real voxelSize, const ReadLimits& limits = {});

}  // namespace gradel::io
