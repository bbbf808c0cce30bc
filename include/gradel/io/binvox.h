// binvox (Min's voxeliser, patrickmin.com/binvox): a text header then run-length data.
//
//   #binvox 1
//   dim D H W          sizes; the data's order is x slowest, then z, then y fastest
//   translate tx ty tz (optional, ignored: gradel places the body with the scene's "position")
//   scale s            (optional, ignored: the scene's "voxel_size" gives the voxel edge)
//   data
//   (value byte, count byte) pairs, count 1..255, covering exactly D*H*W voxels
//
// Axes: binvox's x, y, z become gradel's i, j, k (nx = D, nz = H, ny = W, as binvox_rw and
// viewvox read it); binvox's y is up, like gradel's default gravity.
#pragma once

#include "gradel/io/byte_stream.h"
#include "gradel/io/read_limits.h"
#include "gradel/volume.h"

namespace gradel::io {

/// Reads a binvox file. Non-zero values are filled. InputError for anything malformed.
VoxelVolume readBinvox(ByteStream& in, Real voxelSize, const ReadLimits& limits = {});

}  // namespace gradel::io
