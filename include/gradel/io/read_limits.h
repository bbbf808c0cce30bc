// Limits every reader checks before it allocates: a hostile header claiming 2^31 x 2^31 x 2^31
// voxels or four billion triangles is an InputError, never an allocation or an overflow.
#pragma once

#include <array>
#include <cstdint>
#include <string>

#include "gradel/io/byte_stream.h"
#include "gradel/volume.h"

namespace gradel::io {

struct ReadLimits {
  /// Largest grid edge [voxels] (the scene files' cap too).
  int64_t maxEdge = 4096;
  /// Largest voxel count: 1024^3 (1 GiB of voxels) by default, so 512^3 CT volumes load with
  /// room to spare; fuzz targets lower it to keep each run fast.
  uint64_t maxVoxels = uint64_t(1) << 30;
  /// Largest vertex or triangle count of a mesh file.
  uint64_t maxMeshElements = uint64_t(1) << 26;
  /// Voxelising a mesh (voxelize.h): ray-triangle crossings allowed per axis, at least this many
  /// and at least 64 per ray; more means thousands of overlapping sheets, an InputError.
  uint64_t minRayCrossingCap = uint64_t(1) << 20;
};

/// An empty 3D volume of dims[0] x dims[1] x dims[2] after checking every edge is in
/// [1, maxEdge] and the product is at most maxVoxels; otherwise InputError naming `in` and
/// `what` ("dim", "sizes", ...). Dims arrive as int64 so that negative values are reported as such.
VoxelVolume allocateVolume(const ByteStream& in, const std::array<int64_t, 3>& dims, Real voxelSize,
                           const ReadLimits& limits, const std::string& what);

/// Parses a decimal integer token in full ("12", "-3"); InputError naming `what` otherwise.
int64_t parseIntegerToken(const ByteStream& in, const std::string& token, const std::string& what);
/// Parses a finite decimal number token in full; InputError naming `what` otherwise.
double parseNumberToken(const ByteStream& in, const std::string& token, const std::string& what);

}  // namespace gradel::io
