// libFuzzer target for one reader, chosen at compile time by GRADEL_FUZZ_FORMAT (a VolumeFormat
// name: binvox, vox, nrrd, nifti, raw, obj, stl, ply); cmake/fuzz.cmake builds one binary per
// format. Any InputError is the expected answer to a bad file; anything else (a crash, a
// sanitizer report, another exception type, a leak, an allocation past -rss_limit_mb) is a bug.
//
// Limits are lowered (64^3 voxels, 2^16 mesh elements, resolution 16, 2^14 ray crossings per
// axis when voxelising) so each execution is fast; the checks that enforce them are the same as
// at full size. (With the default crossing floor of 2^20, a 64 KiB PLY repeating one big face
// cost the voxeliser 6 s per execution.)
#include <cstdint>
#include <cstring>

#include "gradel/io/byte_stream.h"
#include "gradel/io/volume_file.h"

#ifndef GRADEL_FUZZ_FORMAT
#error "define GRADEL_FUZZ_FORMAT"
#endif

namespace {

gradel::io::VolumeFileSpec fuzzSpec() {
  gradel::io::VolumeFileSpec s;
  s.limits.maxEdge = 256;
  s.limits.maxVoxels = uint64_t(1) << 18;
  s.limits.maxMeshElements = uint64_t(1) << 16;
  s.limits.minRayCrossingCap = uint64_t(1) << 14;  // = 64 per ray at resolution 16
  s.resolution = 16;
  s.grey.threshold = 1;
  return s;
}

// raw files carry no header, so the first 8 input bytes choose the layout the user would give.
void rawLayoutFromInput(const uint8_t*& data, size_t& size, gradel::io::VolumeFileSpec& s) {
  uint8_t b[8] = {};
  const size_t n = size < 8 ? size : 8;
  std::memcpy(b, data, n);
  data += n;
  size -= n;
  // dims 0..31 (0 exercises the error path); any type; either byte order; 0..15 header bytes.
  s.raw.dims = {b[0] % 32, b[1] % 32, b[2] % 32};
  s.raw.samples.type = gradel::io::ScalarType(b[3] % 10);
  s.raw.samples.bigEndian = b[4] & 1;
  s.raw.headerBytes = b[5] % 16;
  if (b[6] & 1) s.grey.threshold.reset(), s.grey.rangeLo = -double(b[7]), s.grey.rangeHi = double(b[7]);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace gradel::io;
  const VolumeFormat format = parseVolumeFormat(GRADEL_FUZZ_FORMAT);
  VolumeFileSpec spec = fuzzSpec();
  if (format == VolumeFormat::Raw) rawLayoutFromInput(data, size, spec);
  try {
    std::unique_ptr<ByteStream> in = memoryStream(data, size, "fuzz");
    // Compressed input is tried the way readVolumeFile does for .gz files.
    if (size >= 2 && data[0] == 0x1f && data[1] == 0x8b) in = gzipStream(std::move(in));
    const gradel::VoxelVolume v = readVolumeStream(*in, format, spec);
    // Touch the result so a wrong size would be caught by the sanitizers.
    volatile size_t filled = v.countFilled();
    (void)filled;
  } catch (const gradel::InputError&) {
  }
  return 0;
}
