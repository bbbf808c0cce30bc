#include "gradel/io/nifti.h"

#include <nifti1.h>
#include <nifti2.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>

namespace gradel::io {

namespace {

static_assert(sizeof(nifti_1_header) == 348, "nifti1.h layout");
static_assert(sizeof(nifti_2_header) == 540, "nifti2.h layout");

template <class T>
T swapped(T v, bool swap) {
  if (!swap) return v;
  std::array<uint8_t, sizeof(T)> b;
  std::memcpy(b.data(), &v, sizeof(T));
  std::reverse(b.begin(), b.end());
  std::memcpy(&v, b.data(), sizeof(T));
  return v;
}

ScalarType niftiType(const ByteStream& in, int code) {
  switch (code) {
    case NIFTI_TYPE_UINT8: return ScalarType::UInt8;
    case NIFTI_TYPE_INT8: return ScalarType::Int8;
    case NIFTI_TYPE_INT16: return ScalarType::Int16;
    case NIFTI_TYPE_UINT16: return ScalarType::UInt16;
    case NIFTI_TYPE_INT32: return ScalarType::Int32;
    case NIFTI_TYPE_UINT32: return ScalarType::UInt32;
    case NIFTI_TYPE_INT64: return ScalarType::Int64;
    case NIFTI_TYPE_UINT64: return ScalarType::UInt64;
    case NIFTI_TYPE_FLOAT32: return ScalarType::Float32;
    case NIFTI_TYPE_FLOAT64: return ScalarType::Float64;
    default: break;
  }
  in.fail("header: datatype " + std::to_string(code) + " is not supported (expected an integer or real scalar type)");
}

// The fields gradel uses, from either header version.
struct Header {
  std::array<int64_t, 8> dim{};
  int datatype = 0;
  double voxOffset = 0;
  double slope = 0, inter = 0;
  bool bigEndian = false;
};

Header readHeader(ByteStream& in) {
  uint8_t raw[540];
  in.readExact(raw, 348, "NIfTI header");
  int32_t size = 0;
  std::memcpy(&size, raw, 4);
  Header h;
  const bool swap = size == 0x5C010000 || size == 0x1C020000;  // 348 or 540, byte-swapped
  h.bigEndian = swap != (std::endian::native == std::endian::big);
  size = swapped(size, swap);
  if (size == 348) {
    nifti_1_header n;
    std::memcpy(&n, raw, 348);
    if (std::memcmp(n.magic, "ni1", 4) == 0)
      in.fail("header: a two-file (.hdr/.img) NIfTI pair is not supported (use .nii)");
    if (std::memcmp(n.magic, "n+1", 4) != 0) in.fail("header: magic is not 'n+1' (not a NIfTI-1 .nii file)");
    for (int i = 0; i < 8; ++i) h.dim[i] = swapped(n.dim[i], swap);
    h.datatype = swapped(n.datatype, swap);
    h.voxOffset = swapped(n.vox_offset, swap);
    h.slope = swapped(n.scl_slope, swap);
    h.inter = swapped(n.scl_inter, swap);
  } else if (size == 540) {
    in.readExact(raw + 348, 540 - 348, "NIfTI-2 header");
    nifti_2_header n;
    std::memcpy(&n, raw, 540);
    if (std::memcmp(n.magic, "ni2", 4) == 0)
      in.fail("header: a two-file (.hdr/.img) NIfTI pair is not supported (use .nii)");
    if (std::memcmp(n.magic, "n+2\0\r\n\032\n", 8) != 0)
      in.fail("header: magic is not 'n+2' (not a NIfTI-2 .nii file)");
    for (int i = 0; i < 8; ++i) h.dim[i] = swapped(n.dim[i], swap);
    h.datatype = swapped(n.datatype, swap);
    h.voxOffset = double(swapped(n.vox_offset, swap));
    h.slope = swapped(n.scl_slope, swap);
    h.inter = swapped(n.scl_inter, swap);
  } else {
    in.fail("header: sizeof_hdr is " + std::to_string(size) + " (expected 348 for NIfTI-1 or 540 for NIfTI-2)");
  }
  return h;
}

}  // namespace

VoxelVolume readNifti(ByteStream& in, const GreyRule& rule, Real voxelSize, const ReadLimits& limits) {
  const Header h = readHeader(in);
  const uint64_t headerBytes = in.offset();
  if (h.dim[0] < 1 || h.dim[0] > 7) in.fail("header: dim[0] is " + std::to_string(h.dim[0]) + " (expected 1 to 7)");
  std::array<int64_t, 3> dims{1, 1, 1};
  for (int i = 0; i < std::min<int64_t>(3, h.dim[0]); ++i) dims[i] = h.dim[i + 1];
  for (int64_t i = 4; i <= h.dim[0]; ++i)
    if (h.dim[i] < 1)
      in.fail("header: dim[" + std::to_string(i) + "] is " + std::to_string(h.dim[i]) + " (expected >= 1)");
  SampleLayout layout;
  layout.type = niftiType(in, h.datatype);
  layout.bigEndian = h.bigEndian;
  // The standard: scaling applies when scl_slope is non-zero (and, in practice, finite).
  if (h.slope != 0 && std::isfinite(h.slope) && std::isfinite(h.inter)) {
    layout.scale = h.slope;
    layout.offset = h.inter;
  }
  // vox_offset is a float in NIfTI-1; it must be a whole byte count past the header.
  if (!std::isfinite(h.voxOffset) || h.voxOffset < double(headerBytes) || h.voxOffset != std::floor(h.voxOffset) ||
      h.voxOffset > 1e12)
    in.fail("header: vox_offset " + std::to_string(h.voxOffset) + " is not a byte offset at or after the " +
            std::to_string(headerBytes) + "-byte header");
  VoxelVolume v = allocateVolume(in, dims, voxelSize, limits, "header: dim");
  in.skip(uint64_t(h.voxOffset) - headerBytes, "extensions before vox_offset");
  const SampleStats stats = readGreyLevels(in, layout, rule, v);
  if (v.countFilled() == 0) failNothingFilled(in.name(), rule, stats);
  return v;
}

}  // namespace gradel::io
