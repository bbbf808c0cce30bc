#include "gradel/io/raw_volume.h"

namespace gradel::io {

VoxelVolume readRawVolume(ByteStream& in, const RawLayout& layout, const GreyRule& rule, Real voxelSize,
                          const ReadLimits& limits) {
  VoxelVolume v = allocateVolume(in, layout.dims, voxelSize, limits, "dims");
  const uint64_t dataBytes = uint64_t(v.size()) * scalarTypeBytes(layout.samples.type);
  if (const auto left = in.remaining(); left && *left != layout.headerBytes + dataBytes)
    in.fail("size: the file has " + std::to_string(*left) + " bytes; header_bytes " +
            std::to_string(layout.headerBytes) + " + " + std::to_string(layout.dims[0]) + " x " +
            std::to_string(layout.dims[1]) + " x " + std::to_string(layout.dims[2]) + " " +
            scalarTypeName(layout.samples.type) + " samples need " + std::to_string(layout.headerBytes + dataBytes) +
            " (check dims and type)");
  in.skip(layout.headerBytes, "header_bytes");
  const SampleStats stats = readGreyLevels(in, layout.samples, rule, v);
  if (v.countFilled() == 0) failNothingFilled(in.name(), rule, stats);
  return v;
}

}  // namespace gradel::io
