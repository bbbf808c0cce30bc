// Headerless raw volumes: nx * ny * nz samples, x fastest, of a type and byte order the user
// gives (the scene's "dims", "type", "endian", "header_bytes"). The file must hold exactly
// header_bytes + nx*ny*nz*sizeof(type) bytes, so a wrong guess of dims or type is caught.
#pragma once

#include <array>
#include <cstdint>

#include "gradel/io/byte_stream.h"
#include "gradel/io/grey_levels.h"
#include "gradel/io/read_limits.h"
#include "gradel/volume.h"

namespace gradel::io {

struct RawLayout {
  std::array<int64_t, 3> dims{0, 0, 0};  ///< [voxels] nx, ny, nz (nz = 1 for an image).
  SampleLayout samples;                  ///< Type and byte order (scale / offset unused).
  uint64_t headerBytes = 0;              ///< Bytes skipped before the first sample.
};

/// Reads a raw volume; voxels filled by `rule`. InputError on a size mismatch.
VoxelVolume readRawVolume(ByteStream& in, const RawLayout& layout, const GreyRule& rule, Real voxelSize,
                          const ReadLimits& limits = {});

}  // namespace gradel::io
