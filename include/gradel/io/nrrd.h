// NRRD (teem.sourceforge.net/nrrd/format.html), the format of 3D Slicer and teem: a text header
//   NRRD0004
//   type: short          (any of NRRD's integer / float type names)
//   dimension: 3         (2 or 3; a 2D image is one slice, nz = 1)
//   sizes: 256 256 128   (first axis fastest: gradel's x, y, z)
//   encoding: gzip       (raw, gzip / gz, ascii / text / txt)
//   endian: little       (required for multi-byte raw / gzip samples)
//   spacings / space directions / kinds / ... (read for validity, not used: the scene's
//                                              "voxel_size" gives the lattice)
//   byte skip: 0         (raw only; -1, "skip to the last N bytes", is not supported)
//   (blank line, then the data)
// "key:=value" pairs and "#" comments are skipped. Detached headers ("data file:") are not
// supported: the error says so.
#pragma once

#include "gradel/io/byte_stream.h"
#include "gradel/io/grey_levels.h"
#include "gradel/io/read_limits.h"
#include "gradel/volume.h"

namespace gradel::io {

/// Reads an attached-header NRRD; voxels are filled by `rule`. InputError for anything
/// malformed, unsupported, or a volume where no voxel passes the rule.
VoxelVolume readNrrd(ByteStream& in, const GreyRule& rule, Real voxelSize, const ReadLimits& limits = {});

}  // namespace gradel::io
